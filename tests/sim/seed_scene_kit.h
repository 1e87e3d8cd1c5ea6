/* seed_scene_kit.h: the two tests of the upper-state seeds' shared fixtures (test_rod_seed,
 * test_rod_seed_fold): the paper's Gamma = 0.13 scene at N = 61 moved to (phi, Gamma), and a rod
 * routed to its upper state. Include after cmocka.h. */
#ifndef SEED_SCENE_KIT_H
#define SEED_SCENE_KIT_H

#include "cfg_error.h"
#include "rod_route.h"
#include "rod_solver.h"
#include "scene_file.h"

#define BASE_SCENE RIBBON_SOURCE_DIR "/config/scenes/paper-gamma013.ini"

static inline rod_scene scene(double phi_deg, double gamma)
{
    const char *ovr[] = {"mesh.nodes=61"};
    rod_scene sc;
    cfg_error err;
    assert_int_equal(cfg_scene_load(BASE_SCENE, ovr, 1, &sc, &err), CFG_OK);
    sc.fold_angle_rel = 0.0;
    sc.fold_angle_deg = -phi_deg;
    sc.fold_position = gamma;
    return sc;
}

/* A rod for `sc` on its upper state (the route); *s is made on first use and reused. */
static inline rod *routed(const rod_scene *sc, rod_solver **s)
{
    rod *r = NULL;
    assert_int_equal(rod_alloc(sc, &r, NULL, 0), ROD_OK);
    if (!*s) *s = rod_solver_alloc(r);
    assert_non_null(*s);
    rod_route_report rep = {0};
    assert_int_equal(rod_route_to_state(r, *s, sc, +1, &rep), ROD_OK);
    return r;
}

#endif
