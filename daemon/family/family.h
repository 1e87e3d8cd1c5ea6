/* family.h: the family room's face: the calibration fit (sim/rod_fit.h) tested against strips it
 * does not know (issue 32 D). A family of twins is drawn with a fixed seed across a hand-made
 * strip's ranges; each twin is taken through the protocol by static solves (compression, hold,
 * shear: a slow shear keeps the strip on its static branch), filmed by the synthetic camera with
 * the rig's noise and resolution and measured by the real tracker, as mock mode's camera does;
 * the fit then calibrates the scene from what the tracker saw before the shear, and again with
 * the shear up to a fraction of the way to the twin's own snap, and both calibrated predictions
 * are scored against that snap.
 *
 *   family_draw.c     one twin of the family, drawn from (seed, index) alone
 *   family_film.c     a twin's protocol states, rendered and tracked into fit observations
 *   family_case.c     one twin end to end: its snap, the scene's, the two fits and theirs
 *   family_summary.c  the family's medians, band coverage and regime score against the targets
 *   family_bench_main.c  ribbon-fit-family: the whole family on every core, one line */
#ifndef RIBBON_DAEMON_FAMILY_H
#define RIBBON_DAEMON_FAMILY_H

#include <stddef.h>
#include <stdint.h>

#include "rod_fit.h"
#include "rod_fit_snap.h"
#include "scene.h"

/* The ranges a twin is drawn from (issue 32 D), each uniform. */
typedef struct family_ranges {
    double angle_lo_deg, angle_hi_deg; /* |crease angle| of each crease, deg (75, 95) */
    double angle_diff_rel;             /* largest |left - right| / mean of the two (0.05) */
    double hinge_len_lo, hinge_len_hi; /* hinge bending length E I1 / k over l (0.01, 0.20),
                                          drawn log-uniform */
    double youngs_rel;                 /* E within the scene's (1 -+ this) (0.2) */
    double position_rel;               /* each crease within -+ this of the scene's, over l (0.01) */
} family_ranges;

family_ranges family_ranges_default(void);

/* Twin `index` of the family `seed`: the scene with both creases' angles, positions, the hinge
 * stiffness and E drawn from the ranges (the sign of the scene's angle kept), gravity as the
 * scene's (on for the PET strip). Depends only on (seed, index), so twins can be drawn on any
 * core in any order. The scene must have compliant creases. 0, or -1 with the reason. */
int family_draw(const rod_scene *sc, const family_ranges *rg, uint64_t seed, int index, rod_scene *twin,
                char *why, size_t why_len);

/* How a twin is filmed and measured. */
typedef struct family_film_opts {
    int n_compress;        /* frames of the compression, evenly from dl_start to the scene's Delta L (20) */
    double dl_start;       /* Delta L of the first compression frame (the scene's minus 0.05) */
    int n_hold;            /* frames of the hold at the scene's Delta L (20) */
    int n_shear;           /* frames of the shear, evenly in Delta W over (0, dw_stop] (30) */
    double dw_stop;        /* Delta W of the last shear frame (0: no shear frames) */
    int width_px, height_px; /* the rig's camera (640 x 480) */
    double noise_sigma;    /* grey levels (2, the rig files') */
    double blur_sigma_px;  /* (0.8, the rig files') */
    uint64_t seed;         /* the camera's noise */
    int n_shapes;          /* compression frames whose centreline is kept (evenly over the
                              compression, the last at the hold's Delta L; 0: none) */
    int shape_points;      /* points K of each kept centreline (24) */
} family_film_opts;

family_film_opts family_film_opts_default(const rod_scene *sc);

/* What the filming gave: per frame the tracked observation (obs; Delta L, Delta W as the rails
 * put them) and the twin's own projected Delta Z and A there (truth), for the tracker's error. */
typedef struct family_film {
    int n;                 /* frames measured (frames the tracker could not measure are left out) */
    int lost;              /* frames the tracker did not measure */
    int below;             /* compression frames left out: the twin has no upper state there */
    rod_fit_obs *obs;      /* n */
    double *true_dz, *true_a; /* n: the twin's dz_cam, a_cam */
    double dz_rms, a_rms;  /* tracker error over the measured frames: Delta Z (over l), A (rad) */
    double dz_mean, a_mean; /* its mean (bias) */
    int nshapes;           /* centrelines kept (n_shapes of the options, fewer when frames were
                              lost or below the twin's upper states) */
    rod_fit_shape *true_shapes;    /* nshapes: the twin's own x-z projection (rod_shape.h) */
    rod_fit_shape *tracked_shapes; /* nshapes: the tracker's traced centreline (vis_tracker_samples)
                                      at the same frames, mapped
                                      from pixels to the plane y = 0 (the calibration's view model,
                                      depth 0: no shear) and resampled alike */
    double shape_rms;      /* RMS over every point and coordinate of tracked - true, over l */
    double shape_mean_x, shape_mean_z; /* their mean (bias), over l */
} family_film;

/* Films `twin` (its own mesh) through the protocol of o. Arrays are allocated (family_film_free).
 * 0, or -1 with the reason (the twin has no upper state somewhere, a render or tracker failure). */
int family_film_run(const rod_scene *twin, const family_film_opts *o, family_film *out, char *why,
                    size_t why_len);
void family_film_free(family_film *f);

/* One calibration: the fit and its snap. */
typedef struct family_fit {
    int ok;                /* 1: fit and snap prediction ran (else why says what failed) */
    char why[256];
    int nobs;
    rod_fit_result fit;
    rod_fit_snap snap;
    double fit_cpu_s;      /* CPU time of rod_fit_run on the calling thread (one core) */
    double snap_cpu_s;     /* the same of rod_fit_snap_predict (the prediction and its band) */
} family_fit;

/* How each twin is calibrated. */
typedef struct family_case_opts {
    family_film_opts film; /* dw_stop is set per twin from shear_frac */
    double shear_frac;     /* the second fit's shear data stop at this fraction of the twin's own snap (0.8) */
    rod_fit_opts fit;      /* fit options: parameters, priors, noise (default: all six parameters,
                              priors 0.006 on the positions and 12% on E) */
    int noise_from_hold;   /* 1 (default): the noise of each observable from the hold's scatter
                              (0: the fit options' sigmas) */
    int held_at_truth;     /* diagnostic: parameters not fitted are held at the twin's values, not
                              the scene's (what the fit could do if the specimen record knew them) */
    int shape_source;      /* FAMILY_SHAPES_NONE (default), _TRUTH: the twin's own centreline
                              (film.n_shapes frames) plus Gaussian noise of shape_noise, _TRACKER:
                              the tracker's; fed to both fits as rod_fit_opts.shapes */
    double shape_noise;    /* over l, per coordinate (FAMILY_SHAPES_TRUTH) */
    int refresh_shapes;    /* 1 (default): the refresh (the fit with the shear) keeps the centrelines,
                              0: drops them, as the trial's refreshes do (daemon/trial/trial_calibrate.h;
                              with fit.shape_common_mode, the trial's fit 0), and carries the
                              positions by the trial's rule (sim/rod_fit_carry.h) */
} family_case_opts;

enum { FAMILY_SHAPES_NONE, FAMILY_SHAPES_TRUTH, FAMILY_SHAPES_TRACKER };

family_case_opts family_case_opts_default(const rod_scene *sc);

/* One twin scored. */
typedef struct family_case {
    int index;
    rod_scene twin;
    int ok;                /* 1: the truth and the scene's prediction ran and both fits were tried */
    char why[256];
    double truth_dw;       /* the twin's own snap (the fast predictor on the twin), the "measured" one */
    int truth_asym;
    double truth_peak_a;   /* its peak |A| through the snap, rad (the regime rule's measure) */
    double scene_dw;       /* the scene's prediction */
    int scene_asym;
    family_film film_stats;/* tracker error of the shear film (obs arrays freed: NULL) */
    family_fit before, at; /* from compression + hold; then with the shear up to shear_frac of the
                              snap, a refresh started from the first fit's values (from the
                              scene's when the first failed) */
    double sigma_dz, sigma_a; /* the noise the fits weighted the residuals with */
    int nshapes;           /* centrelines the fits were given */
    double shape_rms;      /* the tracker's centreline against the twin's, over l (film_stats') */
    double wall_s;
} family_case;

/* Runs twin `index` of the family: draws it, predicts its snap and the scene's, films it, fits
 * twice. 0 with out filled (out->ok 0 and out->why when the twin itself could not be run). */
int family_case_run(const rod_scene *sc, const family_ranges *rg, uint64_t seed, int index,
                    const family_case_opts *o, family_case *out);

/* The family against the targets (issue 32 D). Errors are |predicted - truth| / truth. */
typedef struct family_summary {
    int twins, ran;            /* drawn; ran end to end */
    int fits_before, fits_at;  /* calibrated predictions made */
    double scene_median, scene_max;
    double before_median, before_max;
    double at_median, at_max;
    double before_in2sd, at_in2sd;  /* share of the truth inside the 2-sigma band */
    double before_z_median, at_z_median; /* median |error| / sigma */
    int regime_scored_before, regime_right_before; /* twins whose band does not reach the boundary */
    int regime_scored_at, regime_right_at;
    double tracker_dz_rms, tracker_a_rms;  /* median over the family, shear films */
    int before_pos_undetermined; /* before-shear fits naming a crease position not determined */
    int at_pos_undetermined;
    double shape_rms;          /* median over the family of the tracker's centreline error, over l
                                  (-1: no shapes kept) */
} family_summary;

void family_summarise(const family_case *c, int n, family_summary *s);

#endif
