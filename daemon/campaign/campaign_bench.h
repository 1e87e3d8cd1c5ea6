/* campaign_bench.h: the simulated campaign (campaign_bench.c; issue 35 part D's test and
 * `ribbonctl plan-bench`): the planner against a bench of twins it does not know.
 *
 * The bench. Every specimen the planner proposes at design (phi, Gamma) is "folded" as a twin:
 * the scene's strip with its creases relaxed by relax_deg (both creases phi - relax) and a more
 * compliant crease (fold_stiffness_factor twin_stiffness_factor instead of the scene's), each
 * crease's angle then off by a uniform random fraction in [-spread, spread] (hand folding). Its
 * regime is "measured" by the sweep's classification (rod_bifurcation_analyse with
 * rod_analysis_opts_classify: the first instability on the upper branch, pitchfork = asymmetric),
 * at the twin's mean crease angle. Why not a mock trial per specimen: the target below is the
 * static codimension-2 boundary, and a dynamic snap at a finite shear rate switches regime at a
 * different Gamma (mock scene, phi 90: Gamma 0.17 snaps symmetrically in `ribbon-sim predict` while
 * the static boundary is 0.1763, the rate lag of docs/simulator.md), so a dynamic measurement would
 * score the rate lag, not the planner; and a mock trial (N = 121 twin, rendering, tracking) costs
 * tens of seconds against a fraction of one here.
 * The compliant crease is by default the rigid-crease model's smaller stiffness factor; with
 * twin_hinge > 0 it is a compliant hinge (folds.hinge_stiffness), which rod_boundary traces since
 * rod_params_apply moves hinged creases (docs/boundary.md "Compliant creases").
 *
 * Dynamic (opts.dynamic). The trial's own measure without the camera: rod_predict in fast mode
 * (adaptive steps, as `ribbon-sim predict --fast`) on the twin at the scene's shear rate, its
 * regime by the rule (peak |A| above snap.asym_threshold). Truth: the twins' mean strip (equal
 * creases at phi - relax, the scene's imperfection) bisected in Gamma on the same measure to
 * DYN_TRUTH_TOL from a bracket around its static Gamma*. Heavy: about 1 s per specimen and 10 per
 * phi for the truth at N = 61.
 *
 * Truth. The twins' mean strip (relaxed, compliant, equal creases) traced with rod_boundary at each
 * design phi (its creases at phi - relax). The planner's model: the scene traced at the design phi.
 *
 * Scoring (opts.truth): against the static truth or the dynamic one, whatever measured the twins
 * (by default the one that matches the measurement: dynamic with opts.dynamic). The result keeps
 * both where they were computed.
 *
 * A campaign: one specimen at a time, each where the planner puts it (calibrated or with the
 * offset fixed at 0), until every phi's experimental boundary (campaign_edge.h) is a closed
 * interval at most stop_width wide, or max_specimens. The located boundary is the experimental
 * edge's estimate (the belief's median where the edge is still open).
 *
 * Calibrations (opts.lab_strip, with calibrate). Each twin yields a calibration as a trial would,
 * from its own observables before the snap, never from the bench's hidden values: its static
 * states through the last 0.05 of the compression (5), the hold (5 frames of one state) and the
 * shear up to fit_shear_frac of its own first instability (or snap, dynamic) (8), their camera
 * Delta Z and A (rod_fit_model_eval on the twin) with Gaussian noise of fit_sigma_dz and
 * fit_sigma_a, fitted by sim/rod_fit from the design's scene (as trial_calibrate: both crease
 * angles with a 10 deg prior, and the hinge stiffness when the start's creases are compliant).
 * Why not the family benchmark's film (daemon/family/: render and track each frame): it costs a
 * second or two per specimen, and its tracker measured the twins to 7e-5 l and 0.006 rad, below the
 * noise added here (the fit's default weights, 0.002 and 0.015 rad), so the direct fit is the
 * cheaper and the more pessimistic stand-in. A fit that ends at a bound or misfits is no
 * calibration (counted), as in a trial. The fits are pooled into the lab strip (campaign_strip.h),
 * its boundary traced (campaign_predicted_trace, cached on the strip's key; traced again when the
 * pooled hinge moves by more than a quarter of its standard error) and read at phi - relaxation;
 * the planner's offset is fitted on top of it. */
#ifndef RIBBON_CAMPAIGN_BENCH_H
#define RIBBON_CAMPAIGN_BENCH_H

#include <stddef.h>

#include "campaign_edge.h"
#include "campaign_strip.h"
#include "scene.h"

#define CAMPAIGN_BENCH_MAX_PHI 8

typedef struct campaign_bench_opts {
    double phi_deg[CAMPAIGN_BENCH_MAX_PHI]; /* design angles (default 60, 90, 120) */
    size_t nphi;
    double relax_deg;             /* deg the twins' creases relaxed (default 6) */
    double twin_stiffness_factor; /* the twins' crease factor (default 3; the mock scene's is 1e4) */
    double twin_hinge;            /* N m/rad: > 0 makes the twins' creases compliant hinges of this
                                     stiffness (folds.hinge_stiffness) instead of the factor; 0
                                     (default): rigid creases with twin_stiffness_factor */
    double spread;                /* each crease off by U(-spread, spread) (default 0.01) */
    int dynamic;                  /* 1: each twin measured by its simulated snap (rod_predict, fast
                                     mode, the regime rule on peak |A|) instead of the
                                     classification, and the truth the dynamic switch of the twins'
                                     mean strip bisected in Gamma on that (see below); 0 (default) */
    int max_specimens;            /* default 15 */
    double stop_width;            /* Gamma, default 0.005 */
    unsigned seed;                /* default 1 */
    int calibrate;                /* the planner's calibration (default 1) */
    int lab_strip;                /* with calibrate: 1 (default) the planner's boundary is the lab
                                     strip's, pooled from the twins' fits; 0: the scene's plus the
                                     offset alone (the planner before issue 35 D's calibration) */
    double fit_hinge_start;       /* N m/rad, the fits' starting hinge on a scene with rigid creases:
                                     NaN (default) 3e-3 when twin_hinge > 0 (the lab knows its
                                     creases are hinges, not how stiff), rigid otherwise; 0: never
                                     a hinge (angles only); > 0: this start */
    double fit_sigma_dz, fit_sigma_a; /* the calibrations' noise (0.002, 0.015 rad) */
    double fit_shear_frac;        /* shear observed up to this fraction of the twin's own first
                                     instability or snap (0.8) */
    int truth;                    /* scored against: 0 (default) the measurement's kind, 1 the
                                     static boundary, 2 the dynamic switch */
} campaign_bench_opts;

campaign_bench_opts campaign_bench_opts_default(void);

typedef struct campaign_bench_result {
    int specimens;                /* used */
    int converged;                /* every phi's interval narrowed to stop_width */
    double truth[CAMPAIGN_BENCH_MAX_PHI], predicted[CAMPAIGN_BENCH_MAX_PHI], located[CAMPAIGN_BENCH_MAX_PHI];
    double max_error;             /* max |located - truth| */
    double offset_mean;           /* the planner's final fitted offset */
    int per_phi[CAMPAIGN_BENCH_MAX_PHI]; /* specimens at each phi */
    double classify_s;            /* wall time of the measurements */
    double wall_s;                /* the whole campaign, the truth's and the model's traces included */
    campaign_obs obs[64];         /* the measured design points, in the order first tried */
    size_t nobs;
    int order[64];                /* specimen k's design point (index into obs) */
    double truth_static[CAMPAIGN_BENCH_MAX_PHI];  /* the twins' mean strip's static Gamma* */
    double truth_dynamic[CAMPAIGN_BENCH_MAX_PHI]; /* its dynamic switch; NaN when not computed */
    int calibrations, calibration_failures; /* twins' fits pooled; fits that failed (why: progress) */
    campaign_lab_strip strip;     /* the final lab strip (n_fits 0: none used) */
    double model[CAMPAIGN_BENCH_MAX_PHI]; /* the planner's last boundary (predicted, or the lab strip's) */
    int traces;                   /* the lab strip's traces */
    campaign_strip_fit fit[64];   /* specimen k's calibration, where has_fit[k] */
    int has_fit[64];
    int trace_failures;           /* traces that failed: the planner kept its boundary */
    char trace_failure[512];      /* the last one's reason */
    double fit_s, trace_s;        /* wall time of the twins' fits and of the lab strip's traces */
} campaign_bench_result;

/* Runs one campaign on the scene (the planner's model). -1 with why when a trace or a
 * classification fails. progress (may be NULL) gets one line per specimen. */
int campaign_bench_run(const rod_scene *scene, const campaign_bench_opts *o, campaign_bench_result *r,
                       void (*progress)(void *u, const char *line), void *u, char *why, size_t why_len);

/* ---- shared with the campaign through the camera (campaign_camera_bench.h) ---- */

/* One twin's hand-folding error, drawn from the bench's generator: each crease off by ul, ur
 * ~ U(-spread, spread) of base_deg (the relaxed angle); the mean crease mean_deg = base (1 + (ul +
 * ur) / 2) and imperfection.fold_angle_rel = (ul - ur) / (1 + (ul + ur) / 2), so the creases are
 * base (1 + ul) and base (1 + ur). Two draws a specimen, ul first. */
typedef struct campaign_twin_draw {
    double ul, ur;      /* relative errors of the creases at Gamma and 1 - Gamma */
    double mean_deg;    /* their mean angle, deg (magnitude) */
    double rel;         /* their relative difference (the scene's fold_angle_rel) */
} campaign_twin_draw;
void campaign_bench_draw(unsigned *rng, double spread, double base_deg, campaign_twin_draw *d);
/* Gamma* of sc at each phi[k] (rod_boundary, the codim-2 point moved to each angle). -1 with why. */
int campaign_bench_trace(const rod_scene *sc, const double *phi, size_t n, double *gamma, char *why, size_t why_len);
/* The dynamic switch (rod_predict fast, the regime rule) of strip mean at crease angle phi (deg),
 * bisected to 5e-4 from [g0 - 0.04, g0 + 0.04] into *g. -1 with why (not bracketed, a predict
 * failed). */
int campaign_bench_dynamic_switch(const rod_scene *mean, double phi, double g0, double *g, char *why, size_t why_len);

#endif
