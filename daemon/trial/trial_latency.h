/* trial_latency.h: where the snap-to-stop time of a live trial goes (issue 34 F).
 *
 * The runner notes each instant on its own way from the snap to the standing shear rail; this
 * file owns those instants, the stop-watch window the rail poller is given, and the stored
 * breakdown event, so the runner keeps only the hooks. All times are trial times (s from the
 * rail clock at the trial's start, t0_mono: CLOCK_MONOTONIC in rig mode, the clock ribbon-rigsim's
 * truth and axes logs use, so an outside tool can line them up). NaN = not reached. */
#ifndef RIBBON_DAEMON_TRIAL_LATENCY_H
#define RIBBON_DAEMON_TRIAL_LATENCY_H

#include <stddef.h>

typedef struct trial_latency {
    double t0_mono;      /* rail clock at the trial's start */
    long onset_frame;    /* the detector's onset frame (last slow frame before the snap) */
    double t_onset;      /* its own (camera) time */
    long det_frame;      /* the detection frame (first frame seen snapping) */
    double t_det;        /* its own (camera) time, as the latency event counts from */
    double t_det_arrival; /* host arrival of the detection frame (NaN: a camera without one) */
    double t_picked;     /* the trial loop took it from the capture ring (it waited there while the
                            loop was behind) */
    double t_tracked;    /* the tracker was done with it */
    double cpu_tracked;  /* s of the loop thread's CPU the tracker took on it (wall minus this: waiting
                            for a CPU) */
    double t_decided;    /* the loop had stored and judged it: the stop is asked for */
    double t_stop_ret;   /* the stop command returned (the rails' lock waited for, command written) */
    double t_stand;      /* the first fresh shear reading standing (its own time) */
} trial_latency;

void trial_latency_init(trial_latency *l, double t0_mono);
/* s of CPU the calling thread has used (CLOCK_THREAD_CPUTIME_ID; NaN when unavailable). */
double trial_latency_thread_cpu_s(void);
/* s the poller should watch the shear after a stop from speed v (mm/s) at accel a (mm/s^2): the
 * deceleration v/a plus 0.5 s for the link and the controller (bounded, so a rail that never
 * reports standing costs only that many fast reads). */
double trial_latency_watch_window_s(double v_mm_s, double a_mm_s2);
/* The breakdown as one line for the trial's events (ms, 0.1 resolution), e.g.
 * "snap-to-stop breakdown: onset frame 1203 -> detection frame 1205 (at 12.3456 s) 33.3 ms; frame ->
 * arrival 1.2 ms -> picked up 0.3 ms -> tracked 3.1 ms (CPU 2.9 ms) -> decided 0.7 ms -> stop returned 0.8 ms -> read standing 55.2 ms; total
 * 61.3 ms; t0_mono 1234.567890". Parts not reached print "n/a". Returns msg. */
const char *trial_latency_format(const trial_latency *l, char *msg, size_t len);

#endif
