/* test_phase_map: ribbond's predicted phase map (daemon/report/phase_map.h) on its own thread:
 * the state before and while it computes, phase_map_start called twice starts one computation,
 * and phase_map_free during the computation returns within a few seconds (cancelled at the next
 * time step, not after the 30 predictions, some 10-20 s); phase_grid_compute with the cancel
 * already set computes nothing and says "cancelled"; a cell without an upper state is marked
 * PLOT_REGIME_NO_UPPER with its fold located. The finished map is checked end to end by
 * test_ribbond_e2e (GET /phase.png). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>
#include <time.h>

#include "plot.h"
#include "trial_report.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void test_cancel_during_computation(void **state)
{
    (void)state;
    rod_scene sc = rod_scene_default();
    phase_map *m = phase_map_create(&sc);
    assert_non_null(m);
    char line[300], why[256];
    phase_map_state(m, line, sizeof line);
    assert_string_equal(line, "not started");
    assert_null(phase_map_grid(m));
    assert_int_equal(phase_map_start(m, why, sizeof why), 0);
    assert_int_equal(phase_map_start(m, why, sizeof why), 0); /* the same computation */
    phase_map_state(m, line, sizeof line);
    assert_true(strncmp(line, "computing ", 10) == 0);
    assert_null(phase_map_grid(m));
    struct timespec pause = {0, 300 * 1000000L};
    nanosleep(&pause, NULL);
    double t0 = now_s();
    phase_map_free(m);
    double dt = now_s() - t0;
    printf("phase_map_free during the computation: %.3f s\n", dt);
    assert_true(dt < 3.0);
}

static void test_grid_cancelled_before_start(void **state)
{
    (void)state;
    rod_scene sc = rod_scene_default();
    atomic_int cancel;
    atomic_init(&cancel, 1);
    phase_grid g;
    char why[256] = "";
    double t0 = now_s();
    assert_int_equal(phase_grid_compute(&sc, 30, 150, 5, 0.08, 0.28, 6, &g, NULL, NULL, &cancel, why, sizeof why), -1);
    assert_true(now_s() - t0 < 1.0);
    assert_non_null(strstr(why, "cancelled"));
    assert_null(g.regime);
}

/* A cell whose prediction fails because there is no upper state is marked so: at phi 150 deg,
 * Gamma 0.24 (N = 41, the map's resolution) the route hits Newton's cap at 90% of the crease ramp;
 * followed from the cell at phi 120 deg, the upper state ends at a fold in phi near 134.9 deg
 * (located, rod_seed_fold.h), so the cell is PLOT_REGIME_NO_UPPER, not "prediction failed"
 * (PLOT_REGIME_UNKNOWN, what it was without the location). The other three cells are predicted.
 * Four cells, about a second. */
static void test_no_upper_state_cell(void **state)
{
    (void)state;
    rod_scene sc = rod_scene_default();
    sc.nodes = 41;
    sc.dt = 0.01;
    phase_grid g;
    char why[256] = "";
    assert_int_equal(phase_grid_compute(&sc, 120, 150, 2, 0.20, 0.24, 2, &g, NULL, NULL, NULL, why, sizeof why), 0);
    for (int k = 0; k < 4; k++) print_message("phi %g Gamma %g: regime %d\n", g.phi_deg[k / 2], g.gamma[k % 2], g.regime[k]);
    assert_int_equal(g.regime[1 * 2 + 1], PLOT_REGIME_NO_UPPER);
    for (int k = 0; k < 3; k++)
        assert_true(g.regime[k] == PLOT_REGIME_ASYMMETRIC || g.regime[k] == PLOT_REGIME_SYMMETRIC ||
                    g.regime[k] == PLOT_REGIME_NO_SNAP);
    phase_grid_free(&g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cancel_during_computation),
        cmocka_unit_test(test_grid_cancelled_before_start),
        cmocka_unit_test(test_no_upper_state_cell),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
