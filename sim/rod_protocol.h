/* rod_protocol.h: the trial protocol simulated end to end, which is what "predict" means:
 * reach the upper state at Delta L (rod_route.h), then shear at the scene's constant rate with
 * the axial gap held, integrating the dynamics by implicit Euler with mass-proportional damping,
 * recording Delta Z, A and A_cam every step, detecting the snap and classifying its pathway.
 *
 * Snap (README "Snap"): the ribbon is snapping at the first step where |d(Delta Z)/dt| exceeds
 * snap.speed (1/s). The snap Delta W is the shear at the last step before that where
 * |d(Delta Z)/dt| was still below a tenth of snap.speed (the onset). The pathway is asymmetric
 * when the peak |A| from the onset until post_snap_time (2 s) of simulated time after detection
 * exceeds snap.asym_threshold (the rule of rod_regime.h, shared with the trial's detector),
 * symmetric otherwise. A run that reaches
 * protocol.shear_max without a snap reports "no snap".
 *
 * Adaptive time stepping: before the snap is detected each step aims at a change of 2e-3 in
 * Delta Z and in A and at a relative growth of |A| of 5% (0.03 once Delta Z moves faster than
 * the onset speed), between dt and 100 dt; a step that overshoots twice over is redone shorter,
 * and one whose Newton solve fails is halved. After detection the step returns to dt. The fast
 * prediction adds a quasi-static start (rod_quasi.h), longer steps after the snap is detected
 * (up to post_snap_dt_max while Delta Z and A change by less than 0.03 per step), and stops
 * following the snap at the end of its first swing (end_after_swing): Delta Z turning round in
 * the lower state. The peak |A| is then that of the passage, without the ringing afterwards
 * (paper Gamma = 0.13 scene: 1.99 rad fast, 1.98 over the fixed run's passage, 2.10 over its
 * 2 s). */
#ifndef RIBBON_SIM_ROD_PROTOCOL_H
#define RIBBON_SIM_ROD_PROTOCOL_H

#include "rod.h"
#include "rod_snapshot.h"

typedef struct rod_sample {
    double t;        /* s since the shear started */
    double dw, dz, a, a_cam, dz_cam;
    double elastic;  /* J, elastic (+ gravity) energy */
    double kinetic;  /* J, kinetic energy of the free DOFs */
    double work;     /* J, work done on the ribbon by the moving clamp so far */
    double damped;   /* J, energy removed by the damping so far */
} rod_sample;

/* Called after every accepted step; return non-zero to stop the run (reported as stopped). */
typedef int (*rod_sample_fn)(void *user, const rod_sample *s, const rod *r);

typedef struct rod_predict_opts {
    int adaptive;          /* 1: adaptive time stepping (fast mode) */
    int quasi_static;      /* with adaptive: start with the quasi-static branch (rod_quasi.h) up
                              to a margin before the first instability (ignored with a ramp) */
    double post_snap_dt_max; /* with adaptive: longest step after the snap is detected, s
                                (0: the scene's dt); steps stay short enough to resolve A */
    double post_snap_time; /* s of simulated time followed after the snap is detected (2) */
    int end_after_swing;   /* 1: stop following the snap when Delta Z turns round at the end of
                              its first swing (the passage to the lower state) instead of after
                              post_snap_time; the peak |A| is then the passage's (fast mode) */
    double adapt_scale;    /* with adaptive: the step control's targets (2e-3, 0.03, 5%) times
                              this (0 counts as 1). The resolution ladder scales them with dt, so
                              a rung's onset is resolved like its dt (daemon/trial/predict_ladder.h) */
    double ramp_time;      /* s over which the shear velocity rises smoothly from 0 to the rate,
                              v = rate (1 - cos(pi t / T)) / 2 (0: starts at full rate) */
    const struct rod_predict_warm *warm; /* NULL: the route and the quasi-static start from
                              Delta W = 0. Else (fast mode) a nearby strip's states to start
                              from (below) */
    rod_sample_fn on_sample;
    void *user;
} rod_predict_opts;

/* A warm start (the band's probes, rod_fit_snap.c): the upper state and a static state on the
 * quasi-static branch of a nearby strip (the same mesh size), each re-solved for this strip by
 * one static Newton solve instead of the route and the quasi-static steps before dw. The answer
 * is the cold start's (the same static states, to the Newton tolerance, and the same grid of
 * quasi-static steps when dw is a multiple of rod_quasi_step) as long as the switch to the
 * dynamics is more than the quasi-static margin after dw; when it is not, or a re-solve fails
 * or leaves the upper branch, the prediction starts again cold (rod_prediction.warm says
 * which). */
typedef struct rod_predict_warm {
    const rod_snapshot *upper; /* at (compression, 0) */
    const rod_snapshot *at;    /* at (compression, dw) */
    double dw;
} rod_predict_warm;

rod_predict_opts rod_predict_opts_default(void);
/* The fast prediction (ribbon-sim predict --fast, bench fast_predict): adaptive, quasi-static
 * start, post-snap steps up to 5 dt (README "Fast mode"). */
rod_predict_opts rod_predict_opts_fast(const rod_scene *sc);

typedef struct rod_prediction {
    int snapped;           /* 1 when a snap was detected */
    double snap_dw;        /* Delta W at the snap onset (valid when snapped) */
    int asymmetric;        /* pathway: 1 asymmetric, 0 symmetric */
    double peak_abs_a;     /* rad, peak |A| during the snap */
    double dz_upper;       /* Delta Z of the upper state before shearing */
    double elastic_upper;  /* J, elastic (+ gravity) energy of that state */
    double dz_final;       /* Delta Z at the end of the run */
    long steps;            /* accepted time steps */
    long rejected;         /* rejected (halved) steps */
    int quasi_solves;      /* static solves of the quasi-static start (0 without it) */
    double dw_switch;      /* Delta W where the dynamics started (0 without the quasi-static start) */
    double sim_time;       /* s of simulated shear time (with a snap: where the run stopped
                              following it) */
    double wall_s;         /* s of wall time for the whole prediction */
    rod_counters count;    /* what was evaluated */
    int stage_route, stage_shear, stage_damping; /* stages that ran */
    int warm;              /* 1: started from opts.warm; 0: cold (none given, or it fell back) */
} rod_prediction;

rod_status rod_predict(const rod_scene *sc, const rod_predict_opts *o, rod_prediction *out,
                       char *why, size_t why_len);

#endif
