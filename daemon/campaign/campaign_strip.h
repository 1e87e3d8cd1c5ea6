/* campaign_strip.h: the lab strip (campaign_strip.c; issue 35 D on issue 32's fits): the systematic
 * part of the specimens' fitted strips pooled into one strip whose boundary the planner traces.
 *
 * Why. The planner's model of the true boundary used to be the scene's Gamma*(phi) plus one offset
 * shared by every phi; a compliant hinge shifts the boundary by +0.019, +0.008, +0.004 at phi 60,
 * 90, 120 (docs/campaign.md): not one offset. Every trial fits its own strip (trials.fit_json:
 * each parameter's scene value, fitted value and standard error, or "not determined"), and each
 * specimen's strip is refitted from all its trials (specimens.calibration_json): one record per
 * specimen, its calibration when it has one (campaign_strip_collect). What the specimens share is
 * pooled here; what differs from specimen to specimen (one crease against the
 * other, the positions) is not systematic and is left to the planner's noise and offset.
 *
 * Pooled, each by its inverse-variance weighted mean over the fits that determined it (fitted,
 * a finite standard error, not at a bound):
 *   relaxation  deg, design angle minus the fit's mean crease magnitude (the creases opened since
 *               folding), per fit (|left| + |right|) / 2 with the standard error (se_l + se_r) / 2
 *               (the two angles of one trial are correlated near +1, docs/calibration.md, and
 *               the correlation is not stored: the mean of the two is the bound). An absolute
 *               shift: the lab strip at design phi has its creases at phi - relaxation. The
 *               design is the specimen's phi_deg, or the fit's scene value without a specimen.
 *   hinge       ln k of the creases' hinge (folds.hinge_stiffness; or the mean of ln k_left and
 *               ln k_right with the mean of their standard errors when each crease had its own)
 *   youngs      ln E (ribbon.youngs_modulus), G / E held
 * Each fit's standard error is floored at half the median of the pooled fits' (no fit weighs more
 * than four typical ones: one overconfident fit would otherwise set the strip). Standard error of
 * a pooled value: 1 / sqrt(sum w), times the Birge ratio sqrt(chi2 / (n - 1)) when that exceeds 1
 * (fits that scatter more than their errors say). A parameter no fit
 * determined stays the scene's (NaN here). Positions are not pooled (each specimen's position is
 * its design, the planner's variable); the creases' difference is not (random by hand).
 *
 * The trace. The lab strip's boundary is the scene with the pooled hinge and E (campaign_strip_
 * apply), traced against the crease angle and read at phi - relaxation (campaign_strip_at), so a
 * new relaxation needs no new trace; the hinge is rounded to 3 significant digits (campaign_strip_
 * key), so a trace cached under the key is the strip's own. With no fit pooled the strip is the
 * scene and the planner is the offset-only one. */
#ifndef RIBBON_CAMPAIGN_STRIP_H
#define RIBBON_CAMPAIGN_STRIP_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "campaign_predicted.h"
#include "rod_fit.h"
#include "scene.h"
#include "store.h"

/* One fit's values of the pooled parameters (NaN: not fitted or not determined). */
typedef struct campaign_strip_fit {
    int64_t trial_id;          /* 0: not from a trial (the bench); a calibration's: its after_trial */
    int from_calibration;      /* 1: a specimen's calibration (specimens.calibration_json), 0: a trial's fit */
    double design_phi_deg;     /* the specimen's design angle (magnitude); NaN: the fit's scene value */
    double angle_mean_deg;     /* fitted mean crease magnitude (|left| + |right|) / 2 */
    double angle_se_deg;
    double angle_scene_deg;    /* the fit's scene mean magnitude */
    double ln_hinge, ln_hinge_se; /* ln(k / (N m/rad)) and its standard error */
    double hinge_scene;        /* N m/rad, the fit's start (its scene's k); NaN without a hinge */
    double ln_youngs, ln_youngs_se; /* ln(E / Pa) */
} campaign_strip_fit;

/* A fit_json object (trial_calibrated_json's: {"ok": true, "parameters": [{"key", "scene",
 * "fitted", "se", "se_kind", "determined", "at_bound"}, ...]}) into out. design_phi_deg: the
 * specimen's (NaN: none). Returns 1 when some parameter is usable, 0 when none is (a failed fit,
 * every parameter undetermined or at a bound), -1 with why on a malformed record. */
int campaign_strip_fit_parse(const json_t *fit, double design_phi_deg, campaign_strip_fit *out, char *why,
                             size_t why_len);
/* A specimen's calibration record (trial_specimen_calib.h's: {"after_trial", "parameters": [{"key",
 * "start", "value", "se", "se_kind", "determined", "at_bound"}, ...], ...}; start and value may be
 * null) into out, from_calibration 1 and trial_id its after_trial. Returns as fit_parse. */
int campaign_strip_calibration_parse(const json_t *cal, double design_phi_deg, campaign_strip_fit *out, char *why,
                                     size_t why_len);
/* The same from a fit's result in memory (the bench). Returns 1 or 0 as above. */
int campaign_strip_fit_from_result(const rod_fit_result *r, double design_phi_deg, campaign_strip_fit *out);

/* The pooled strip. */
typedef struct campaign_lab_strip {
    int n_fits;                    /* fits with at least one usable parameter */
    int n_calibrations;            /* of them, specimens' calibrations (the rest trials' fits) */
    int n_relax, n_hinge, n_youngs; /* fits that determined each */
    double relax_deg, relax_se;    /* 0 and NaN when none */
    double hinge, hinge_se_rel;    /* N m/rad (rounded, campaign_strip_key); NaN: the scene's creases */
    double youngs, youngs_se_rel;  /* Pa (rounded); NaN: the scene's */
} campaign_lab_strip;

void campaign_strip_pool(const campaign_strip_fit *fits, size_t n, campaign_lab_strip *out);
/* The scene with the strip's hinge and E (relaxation not applied: see campaign_strip_at). */
void campaign_strip_apply(const rod_scene *sc, const campaign_lab_strip *ls, rod_scene *out);
/* The strip's key for a trace cache: "hinge=K youngs=E" with the rounded values ("scene" for a
 * parameter left at the scene's). */
void campaign_strip_key(const campaign_lab_strip *ls, char *out, size_t out_len);
/* 1 when the strip's trace differs from the scene's (a hinge or E pooled). */
int campaign_strip_needs_trace(const campaign_lab_strip *ls);
/* One line saying which strip: "the scene's (no calibration in the store)" or "creases relaxed
 * 5.82 +- 0.31 deg (8 fits), hinge 4.95e-03 N m/rad +- 6.1% (8 fits), E the scene's". */
void campaign_strip_describe(const campaign_lab_strip *ls, char *out, size_t out_len);
/* Gamma* of the lab strip at design phi: curve (the strip's trace) at phi - relaxation. 0, or -1
 * with why (outside the curve's range). */
int campaign_strip_at(const campaign_predicted *curve, const campaign_lab_strip *ls, double phi_deg, double *gamma,
                      char *why, size_t why_len);

/* The lab strip's boundary: lab (campaign_strip_apply's scene) traced over [phi_lo, phi_hi]
 * (campaign_predicted_trace) from its codim-2 point near (phi0, g[i]), trying the starts g[0..ng)
 * in order until the curve covers every need[j] - relaxation: the search for the codim-2 point
 * lands on the boundary's nearest point, and from a start far from it (the scene's Gamma*, when
 * the hinge raised the boundary by 0.01) it can land where the continuation in phi cannot go on
 * (measured: mock scene, k 3.51e-3, N = 61, from Gamma 0.1763 at 90 deg; from 0.185 it goes).
 * 0 with *out, or -1 with why (each start's reason, the last one's in full). */
int campaign_strip_trace(const rod_scene *lab, const campaign_lab_strip *ls, double phi0, const double *g, size_t ng,
                         double phi_lo, double phi_hi, const double *need, size_t nneed, campaign_predicted *out,
                         char *why, size_t why_len);

/* Every usable fit in the store, each with its specimen's design angle: one per specimen from its
 * calibration (specimens.calibration_json, refitted from all its finished trials after each one,
 * trial_specimen_calib.h: the newest; a failed refit keeps the one before) when that determined
 * some parameter, in place of its trials' fits; the trials' fit_json (issue 32 B) of specimens
 * without a usable calibration, and of trials without a specimen. Why: a specimen's trials are one
 * strip, and its calibration pools their frames in one fit; counting each trial's own fit beside
 * it would weigh a specimen by how often it was trialled, and a single trial's fit sees fewer
 * frames. *out malloc'ed (free()), *n of them; *n_failed counts trials (of specimens without a
 * calibration) whose stored fit failed or determined nothing. 0, or -1 with why (a malformed
 * record, named). */
int campaign_strip_collect(store *st, campaign_strip_fit **out, size_t *n, int *n_failed, char *why, size_t why_len);

#endif
