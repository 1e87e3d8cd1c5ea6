/* test_trial_latency: the snap-to-stop breakdown event (issue 34 F): each span is the difference of
 * its two instants (ms, 0.1), the decision counts from the frame when no arrival is known (a paced
 * mock camera: no arrival, pick-up or tracking time), a part not reached prints n/a, the line fits the runner's 320-byte event with
 * the largest frame numbers and times, and the stop watch's window is v/a + 0.5 s. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "trial_latency.h"

static void spans_and_missing_parts(void **state)
{
    (void)state;
    trial_latency l;
    trial_latency_init(&l, 1234.5);
    l.onset_frame = 1203;
    l.det_frame = 1205;
    l.t_onset = 20.0;
    l.t_det = 20.0333;
    l.t_det_arrival = 20.0345;
    l.t_picked = 20.0348;
    l.t_tracked = 20.0379;
    l.cpu_tracked = 0.0029;
    l.t_decided = 20.0386;
    l.t_stop_ret = 20.0394;
    char msg[320];
    trial_latency_format(&l, msg, sizeof msg);
    printf("# %s\n", msg);
    assert_non_null(strstr(msg, "onset frame 1203 -> detection frame 1205 (at 20.0333 s) 33.3 ms"));
    assert_non_null(strstr(msg, "frame -> arrival 1.2 ms -> picked up 0.3 ms -> tracked 3.1 ms (CPU 2.9 ms) -> decided 0.7 ms -> stop returned 0.8 ms"));
    assert_non_null(strstr(msg, "-> read standing n/a; total n/a; t0_mono 1234.500000"));
    l.t_stand = 20.0946;
    trial_latency_format(&l, msg, sizeof msg);
    assert_non_null(strstr(msg, "-> read standing 55.2 ms; total 61.3 ms"));
    l.t_det_arrival = l.t_picked = l.t_tracked = l.cpu_tracked = NAN; /* no camera: the decision counts from the frame */
    trial_latency_format(&l, msg, sizeof msg);
    assert_non_null(strstr(msg, "arrival n/a -> picked up n/a -> tracked n/a -> decided 5.3 ms"));
}

static void fits_an_event(void **state)
{
    (void)state;
    trial_latency l;
    trial_latency_init(&l, 99999999.123456);
    l.onset_frame = l.det_frame = 2147483647L;
    l.t_onset = l.t_det = l.t_det_arrival = l.t_picked = l.t_tracked = l.t_decided = l.t_stop_ret = -99999.0;
    l.cpu_tracked = 99999.0;
    l.t_stand = 99999.0;
    char msg[320];
    trial_latency_format(&l, msg, sizeof msg);
    assert_true(strlen(msg) < sizeof msg - 1);
    assert_non_null(strstr(msg, "t0_mono 99999999.123456"));
    char tiny[8];
    trial_latency_format(&l, tiny, sizeof tiny); /* truncated, terminated */
    assert_int_equal(strlen(tiny), 7);
}

static void watch_window(void **state)
{
    (void)state;
    assert_true(fabs(trial_latency_watch_window_s(10.0, 200.0) - 0.55) < 1e-12);
    assert_true(fabs(trial_latency_watch_window_s(-10.0, 200.0) - 0.55) < 1e-12);
    assert_true(fabs(trial_latency_watch_window_s(10.0, 0.0) - 0.5) < 1e-12);
    assert_true(fabs(trial_latency_watch_window_s(1e9, 1.0) - 5.5) < 1e-12); /* capped */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(spans_and_missing_parts),
        cmocka_unit_test(fits_an_event),
        cmocka_unit_test(watch_window),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
