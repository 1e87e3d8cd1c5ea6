/* campaign_camera_bench.h: the simulated campaign through the camera (campaign_camera_bench.c;
 * issue 35 part D, `ribbonctl plan-bench --camera`). Where campaign_bench.h classifies each
 * proposed specimen with the simulator, here every specimen goes the lab's whole way in mock mode:
 *
 *   plan      campaign_plan_run on the measured regimes read back from the store
 *             (campaign_phase_collect), one proposal, stored (store_plan_add_batch);
 *   approve   POST /plan/ID/approve through campaign_route: the specimen C-k, an operator step
 *             ("fold and mount ...; measured angles?") and a trial of it, queued;
 *   fold      the specimen is made as a twin of the bench's family: the rig file's scene with its
 *             creases relaxed by relax_deg and compliant hinges of twin_hinge N m/rad (what the
 *             planner does not know), each crease then off by U(-spread, spread) of its angle
 *             (campaign_bench_draw: the same draws, from the same seed, as plan-bench);
 *   confirm   the queue (campaign_queue.c, its own thread) reaches the operator step; the harness
 *             confirms it with the angles the lab would measure at folding (the design phi with
 *             the specimen's folding error; the relaxation comes later and is not measured);
 *   trial     the queue starts the trial: the rig file (mock mode) with the specimen's keys and
 *             the twin's keys for this specimen (twin.folds.angle_deg, .imperfection.fold_angle_rel,
 *             .folds.hinge_stiffness), run by trial_session on mock rails on a virtual clock: the
 *             twin simulated under the rails, rendered, tracked, the snap and its regime detected
 *             from the video, everything stored;
 *   read      the measured regime from the stored trial, the twin's own truth from its event.
 * until every phi's experimental boundary is closed and at most stop_width wide, or
 * max_specimens. The queue's start_trial is the harness's (a twin per specimen: ribbond's API
 * refuses twin keys, since in ribbond the twin is the bench's, not a trial's); everything else is
 * the daemon's own code.
 *
 * Truths (campaign_camera_truth): the twins' mean strip (equal creases at phi - relax, the hinge,
 * the twin's mesh) (a) traced statically with rod_boundary, as the issue states, and (b) its dynamic
 * switch: the fast predictor's regime at the rig's shear speed, bisected to 5e-4
 * (campaign_bench_dynamic_switch). The planner's model: the lab strip's boundary (as ribbonctl
 * plan), or with strip 0 the rig file's scene traced at each phi. */
#ifndef RIBBON_CAMPAIGN_CAMERA_BENCH_H
#define RIBBON_CAMPAIGN_CAMERA_BENCH_H

#include <stddef.h>
#include <stdint.h>

#include "campaign_bench.h"
#include "campaign_strip.h"

#define CAMPAIGN_CAMERA_MAX_SPECIMENS 32
#define CAMPAIGN_CAMERA_MAX_SETS 16
/* A twin's regime is clear when its peak |A| is below threshold / CLEAR or above threshold * CLEAR:
 * the regime is a threshold on a smooth peak |A| (docs/campaign.md), and between those the camera's
 * projection and its 30 frames a second may read it either way. */
#define CAMPAIGN_CAMERA_CLEAR 2.0

typedef struct campaign_camera_opts {
    campaign_bench_opts bench;   /* phi_deg, nphi, relax_deg, twin_hinge (here default 5e-3, mock.ini's
                                    [twin]), spread, max_specimens, stop_width, seed, calibrate;
                                    dynamic and twin_stiffness_factor are not used */
    const char *rig_path;        /* a mock-mode rig file (config/mock.ini) */
    const char *sets[CAMPAIGN_CAMERA_MAX_SETS]; /* its overrides ("section.key=value"), applied first */
    int n_sets;
    const char *dir;             /* an existing directory: the campaign's store and videos go here */
    const char *name;            /* the store's and videos' stem in dir (default "campaign") */
    double trial_timeout_s;      /* wall s one specimen (its queue items) may take (default 1200) */
    int keep_videos;             /* 0 (default): each trial's video is removed once its result is read
                                    (about 56 MB a trial); the store keeps every sample and event */
    int strip;                   /* 1 (default): the calibrated campaign plans from the lab strip
                                    (campaign_strip.h: the specimens' calibrations, else their trials'
                                    fits, read from the campaign's store before each proposal) and the
                                    offsets, as ribbonctl plan does; 0: from the scene's boundary and the
                                    offsets (the bench's default before) */
} campaign_camera_opts;

campaign_camera_opts campaign_camera_opts_default(void);

typedef struct campaign_camera_truth {
    double predicted[CAMPAIGN_BENCH_MAX_PHI];   /* the planner's model: the rig scene's Gamma* */
    double statik[CAMPAIGN_BENCH_MAX_PHI];      /* the twins' mean strip, rod_boundary */
    double dynamic[CAMPAIGN_BENCH_MAX_PHI];     /* its dynamic switch; NaN when not asked */
    int nodes;                                  /* the mean strip's mesh */
    double wall_s;
} campaign_camera_truth;

/* The model's and the twins' boundaries at o's phi; dynamic 0 leaves truth->dynamic NaN. -1 with
 * why (the rig file, a trace, a bisection). */
int campaign_camera_truth_trace(const campaign_camera_opts *o, int dynamic, campaign_camera_truth *truth, char *why,
                                size_t why_len);

typedef struct campaign_camera_specimen {
    char name[16];               /* C-1, C-2, ... */
    double phi_deg, gamma;       /* the design (the proposal) */
    double twin_left_deg, twin_right_deg;         /* the twin's creases, magnitudes */
    double twin_mean_deg, twin_rel;               /* its keys: |folds.angle_deg|, imperfection.fold_angle_rel */
    double measured_left_deg, measured_right_deg; /* confirmed at the operator step */
    int64_t proposal_id, trial_id;
    char regime[16];             /* measured, from the stored trial: asymmetric, symmetric, no snap, unknown */
    char truth[16];              /* the twin's own, from its event ("" when missing) */
    double snap_dw, truth_dw;    /* NaN when none */
    double truth_peak_a;         /* rad, the twin's own peak |A| over the passage (its event); NaN when none */
    double wall_s;               /* from approval to the trial's end */
} campaign_camera_specimen;

typedef struct campaign_camera_result {
    int specimens;               /* used */
    int converged;               /* every phi's interval closed and at most stop_width */
    double located[CAMPAIGN_BENCH_MAX_PHI]; /* the experimental edge's estimate (else the belief's median) */
    double err_static, err_dynamic; /* max |located - truth| over phi (NaN without that truth) */
    double offset_mean;          /* the planner's final fitted offset (shared) */
    double offsets[CAMPAIGN_BENCH_MAX_PHI]; /* its final per-phi offsets, Gamma*_j - model_j */
    double spread_mean;          /* its final spread of the per-phi offsets */
    int agree;                   /* trials whose measured regime is the twin's own */
    double asym_threshold;       /* rad, the regime rule's (the scene's snap.asym_threshold) */
    int undecided;               /* trials whose snap the camera could not read either way (stored
                                    without a measured regime; the planner skips them) */
    int clear, clear_agree, clear_undecided; /* trials whose twin's peak |A| is not within a factor
                                    CAMPAIGN_CAMERA_CLEAR of the threshold, and of them those that agree
                                    and those undecided */
    double trials_s;             /* wall s of the specimens' queue items */
    double wall_s;               /* the campaign (the truths not included) */
    campaign_lab_strip strip;    /* opts.strip: the last lab strip pooled (n_fits 0: none) */
    double model[CAMPAIGN_BENCH_MAX_PHI]; /* the boundary the last plan was made from */
    int strip_traces, strip_failures; /* the strip's traces, and the times its model could not be
                                    made (the one before kept; strip_failure says the last why) */
    char strip_failure[600];
    campaign_camera_specimen sp[CAMPAIGN_CAMERA_MAX_SPECIMENS];
} campaign_camera_result;

/* Per design phi[0..n) of r's specimens: used[j] specimens at phi[j], agree[j] of them whose
 * measured regime is the twin's own (a specimen without the twin's truth never agrees). */
void campaign_camera_per_phi(const campaign_camera_result *r, const double *phi, size_t n, int *used, int *agree);

/* One campaign, calibrated or not (o->bench.calibrate), in a new store dir/NAME-cal.db or
 * NAME-uncal.db (an existing one is refused: a campaign starts from nothing). progress (may be
 * NULL) gets one line per step. -1 with why: the rig file (mock mode only), the store, a refused
 * approval, a trial that failed or ran past trial_timeout_s (aborted: its rails stopped). */
int campaign_camera_run(const campaign_camera_opts *o, const campaign_camera_truth *truth, campaign_camera_result *r,
                        void (*progress)(void *u, const char *line), void *u, char *why, size_t why_len);

#endif
