/* rod_bifurcation.c: the scene-level analysis of rod_bifurcation.h: route to the upper state,
 * primary branch, branch switching at the first pitchfork, regime. */
#include "rod_bifurcation.h"
#include "rod_observe.h"
#include "rod_route.h"
#include "rod_solver.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

rod_analysis_opts rod_analysis_opts_default(void)
{
    rod_analysis_opts o;
    memset(&o, 0, sizeof o);
    o.cont = rod_cont_opts_default();
    o.keep_imperfection = 0;
    o.switch_branches = 1;
    o.switch_offset = 0.01;
    return o;
}

rod_analysis_opts rod_analysis_opts_classify(void)
{
    rod_analysis_opts o = rod_analysis_opts_default();
    o.cont.max_negative = 0;
    o.switch_branches = 0;
    return o;
}

void rod_analysis_free(rod_analysis *a)
{
    for (int b = 0; b < a->nbranches; b++) rod_branch_free(&a->branches[b]);
    a->nbranches = 0;
}

/* Copies a solved state (same scene, so the same mesh) into r: q and frames. */
static void copy_state(const rod *from, rod *r)
{
    memcpy(r->q, from->q, sizeof(double) * (size_t)r->ndof);
    memcpy(r->d1, from->d1, sizeof(double[3]) * (size_t)(r->n - 1));
    memcpy(r->d2, from->d2, sizeof(double[3]) * (size_t)(r->n - 1));
    memcpy(r->tref, from->tref, sizeof(double[3]) * (size_t)(r->n - 1));
    memcpy(r->mref, from->mref, sizeof(double) * (size_t)r->n);
}

rod_status rod_bifurcation_analyse(const rod_scene *scene, const rod_analysis_opts *o, rod_analysis *out, char *why,
                                   size_t why_len)
{
    return rod_bifurcation_analyse_from(scene, o, NULL, out, why, why_len);
}

rod_status rod_bifurcation_analyse_from(const rod_scene *scene, const rod_analysis_opts *o, const rod *start,
                                        rod_analysis *out, char *why, size_t why_len)
{
    double t0 = wall_now();
    rod_analysis_opts def = rod_analysis_opts_default();
    if (!o) o = &def;
    memset(out, 0, sizeof *out);
    out->first = -1;
    out->regime = "none";
    rod_scene sc = *scene;
    char key[64], msg[224];
    if (rod_scene_require_symmetric(&sc, msg, sizeof msg, key, sizeof key)) {
        snprintf(why, why_len, "%s: %s", key, msg);
        return ROD_ERR_SCENE;
    }
    if (!o->keep_imperfection) sc.fold_angle_rel = 0.0;
    out->fold_angle_rel = sc.fold_angle_rel;
    rod *r = NULL;
    rod_status st = rod_alloc(&sc, &r, why, why_len);
    if (st != ROD_OK) return st;
    rod_solver *s = rod_solver_alloc(r);
    rod_tracer *t = NULL;
    double *k1 = malloc(sizeof(double) * (size_t)r->n);
    if (!s || !k1) {
        st = ROD_ERR_ALLOC;
        if (why) snprintf(why, why_len, "out of memory allocating the simulator workspace");
        goto done;
    }
    rod_route_report rr = {0};
    if (start) {
        if (start->n != r->n || start->length != r->length) {
            st = ROD_ERR_SCENE;
            if (why) snprintf(why, why_len, "the start state is not of this scene's mesh (%d nodes, not %d)", start->n, r->n);
            goto done;
        }
        copy_state(start, r);
        rod_newton_opts no = rod_newton_opts_static(&sc);
        no.positive_definite = 1;
        rod_newton_report nr;
        st = rod_newton_solve(r, s, &no, &nr);
        rr.reached = st == ROD_OK ? 1.0 : 0.0;
    } else {
        st = rod_route_to_state(r, s, &sc, +1, &rr);
    }
    out->route_wall_s = wall_now() - t0;
    if (st != ROD_OK && start) {
        if (why) snprintf(why, why_len, "the given start state does not solve at Delta L = %g (%s)", sc.compression,
                          rod_status_message(st));
        goto done;
    }
    if (st != ROD_OK) {
        if (why)
            snprintf(why, why_len, "could not reach the upper state at Delta L = %g (%s, %.0f%% of the route done)",
                     sc.compression, rod_status_message(st), 100.0 * rr.reached);
        goto done;
    }
    rod_obs ob;
    rod_observe(r, k1, &ob);
    out->dz_upper = ob.dz;
    if (!(ob.dz > 0.0)) {
        st = ROD_ERR_BRANCH_LOST;
        if (why) snprintf(why, why_len, "the route ended with Delta Z = %g, not in the upper state", ob.dz);
        goto done;
    }
    rod_cont_opts co = o->cont;
    co.tolerance = sc.tolerance;
    rod_load load = {ROD_LOAD_SHEAR, sc.compression, 0.0};
    t = rod_tracer_alloc(r, &load, &co);
    if (!t) {
        st = ROD_ERR_ALLOC;
        if (why) snprintf(why, why_len, "out of memory allocating the continuation workspace");
        goto done;
    }
    rod_branch *b0 = &out->branches[out->nbranches++];
    b0->id = 0;
    b0->parent_event = -1;
    rod_trace_branch(t, 0.0, +1, b0);

    int ne;
    const rod_event *ev = rod_tracer_events(t, &ne);
    for (int e = 0; e < ne; e++)
        if (ev[e].branch == 0 && ev[e].n_negative_before == 0) {
            out->first = e;
            break;
        }
    if (o->switch_branches)
        for (int e = 0; e < ne && out->nbranches < ROD_ANALYSIS_MAX_BRANCHES; e++) {
            if (ev[e].branch != 0 || ev[e].kind != ROD_EVENT_PITCHFORK) continue;
            /* An unfolded (imperfect) pitchfork is a limit point: the primary branch itself
             * turns onto the asymmetric branch there, so there is nothing to switch to. */
            if (ev[e].fold) break;
            rod_branch *bs = &out->branches[out->nbranches];
            bs->id = out->nbranches++;
            bs->parent_event = e;
            rod_trace_switch(t, e, +1.0, o->switch_offset, bs);
            ev = rod_tracer_events(t, &ne);
            break; /* the first pitchfork's branch is the one the asymmetric snap follows */
        }
    ev = rod_tracer_events(t, &ne);
    out->worst_residual = rod_tracer_worst_residual(t);
    out->nevents = ne;
    memcpy(out->events, ev, sizeof(rod_event) * (size_t)ne);
    if (out->first >= 0) {
        rod_event_kind k = out->events[out->first].kind;
        out->regime = k == ROD_EVENT_PITCHFORK ? "asymmetric" : k == ROD_EVENT_SADDLE_NODE ? "symmetric" : "none";
    }
    st = ROD_OK;

done:
    if (r) out->count = r->count;
    out->wall_s = wall_now() - t0;
    rod_tracer_free(t);
    free(k1);
    rod_solver_free(s);
    rod_free(r);
    if (st != ROD_OK) rod_analysis_free(out);
    return st;
}
