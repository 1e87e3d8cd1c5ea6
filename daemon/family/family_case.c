/* family_case.c: one twin of the family end to end (family.h): drawn, its own snap (the fast
 * predictor on the twin: what the rig would measure, mock mode's "twin truth"), the scene's
 * prediction, one film of the protocol up to shear_frac of the way to the twin's snap, and two
 * calibrations from that film: from the compression and hold only (the frames at Delta W = 0,
 * what the runner has before the shear starts) and from every frame (the shear up to
 * shear_frac). Each calibration is rod_fit_run then rod_fit_snap_predict, as `ribbon-sim fit`. */
#include "family.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "rod_fit_carry.h"
#include "rod_protocol.h"

family_case_opts family_case_opts_default(const rod_scene *sc)
{
    family_case_opts o;
    o.film = family_film_opts_default(sc);
    o.shear_frac = 0.8;
    o.noise_from_hold = 1;
    o.fit = rod_fit_opts_default();
    /* Every parameter the twins differ in: the angles and the hinge free (the specimen record
       knows them only to the family's ranges), the positions and E with the specimen record's
       tolerances as priors (a uniform -+ 1% of l and -+ 20% have standard deviations 0.0058 and
       0.115). Without the priors the camera does not determine them (docs/calibration.md). */
    /* The six strip keys the twins differ in (not the view's offset, and one hinge for both
       creases, not the per-crease keys added after this default was written: fitting all of
       them was refused by rod_fit_run) */
    for (int k = ROD_FIT_ANGLE_LEFT; k <= ROD_FIT_YOUNGS; k++) o.fit.fit[k] = 1;
    o.fit.fit[ROD_FIT_HINGE] = !rod_scene_hinge_rigid(sc);
    o.fit.prior_sigma[ROD_FIT_POSITION_LEFT] = o.fit.prior_sigma[ROD_FIT_POSITION_RIGHT] = 0.006;
    o.fit.prior_sigma[ROD_FIT_YOUNGS] = log1p(0.12);
    /* The angles and the hinge with the specimen record's ranges as priors too (the family's: an
       angle uniform in 75..95 deg is 7.6 deg RMS from the scene's 90, a hinge length log-uniform
       in 1..20% of l is 0.88 RMS in ln k from the scene's 3.75%): without them the compression
       and hold leave the hinge (and in some twins the angles) not determined and the snap's band
       before the shear unbounded (rod_fit_band.h) */
    o.fit.prior_sigma[ROD_FIT_ANGLE_LEFT] = o.fit.prior_sigma[ROD_FIT_ANGLE_RIGHT] = 7.6;
    o.fit.prior_sigma[ROD_FIT_HINGE] = 0.88;
    o.shape_source = FAMILY_SHAPES_NONE;
    o.shape_noise = 0.001;
    o.refresh_shapes = 1;
    return o;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int predict(const rod_scene *sc, int *snapped, double *dw, int *asym, double *peak, char *why, size_t why_len)
{
    rod_predict_opts po = rod_predict_opts_fast(sc);
    rod_prediction p;
    rod_status st = rod_predict(sc, &po, &p, why, why_len);
    if (st != ROD_OK) return -1;
    *snapped = p.snapped;
    *dw = p.snap_dw;
    *asym = p.asymmetric;
    if (peak) *peak = p.peak_abs_a;
    return 0;
}

static double cpu_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void calibrate(const rod_scene *sc, const rod_fit_obs *obs, int n, const rod_fit_opts *fo, family_fit *f)
{
    memset(f, 0, sizeof *f);
    f->nobs = n;
    double c0 = cpu_s();
    /* With shapes, started where the fit without them ends (rod_fit_opts.start), as the fit beside a
       trial does (daemon/trial/trial_calibrate.c): the shapes' cost is less convex. */
    rod_fit_opts o1 = *fo, o0 = *fo;
    rod_fit_result r0;
    o0.shapes = NULL;
    o0.nshapes = 0;
    if (fo->nshapes > 0 && !fo->start && rod_fit_run(sc, obs, n, &o0, &r0, f->why, sizeof f->why) == ROD_OK &&
        !r0.misfit)
        o1.start = r0.u;
    rod_status st = rod_fit_run(sc, obs, n, &o1, &f->fit, f->why, sizeof f->why);
    f->fit_cpu_s = cpu_s() - c0;
    if (st != ROD_OK) return;
    c0 = cpu_s();
    st = rod_fit_snap_predict(sc, &f->fit, &f->snap, f->why, sizeof f->why);
    f->snap_cpu_s = cpu_s() - c0;
    if (st != ROD_OK) return;
    if (!f->snap.snapped) {
        snprintf(f->why, sizeof f->why, "the fitted strip does not snap before protocol.shear_max");
        return;
    }
    f->ok = 1;
}

/* The tracker's noise as a trial can measure it: the scatter of the hold's frames (one state,
   filmed n_hold times), floored at a tenth of the defaults (a hold the tracker sees identically
   would otherwise claim infinite precision). */
static void hold_noise(const rod_scene *twin, const rod_fit_obs *obs, int n, rod_fit_opts *fo)
{
    double sz = 0, sa = 0, mz = 0, ma = 0;
    int m = 0;
    for (int k = 0; k < n; k++)
        if (obs[k].dw == 0.0 && obs[k].dl == twin->compression) {
            mz += obs[k].dz;
            ma += obs[k].a;
            m++;
        }
    if (m < 5) return;
    mz /= m;
    ma /= m;
    for (int k = 0; k < n; k++)
        if (obs[k].dw == 0.0 && obs[k].dl == twin->compression) {
            sz += (obs[k].dz - mz) * (obs[k].dz - mz);
            sa += (obs[k].a - ma) * (obs[k].a - ma);
        }
    rod_fit_opts d = rod_fit_opts_default();
    fo->sigma_dz = fmax(sqrt(sz / (m - 1)), 0.1 * d.sigma_dz);
    fo->sigma_a = fmax(sqrt(sa / (m - 1)), 0.1 * d.sigma_a);
}

int family_case_run(const rod_scene *sc, const family_ranges *rg, uint64_t seed, int index,
                    const family_case_opts *o, family_case *out)
{
    memset(out, 0, sizeof *out);
    out->index = index;
    double t0 = now_s();
    char why[512] = "";
    int snapped = 0;
    if (family_draw(sc, rg, seed, index, &out->twin, why, sizeof why) != 0) goto fail;
    if (predict(&out->twin, &snapped, &out->truth_dw, &out->truth_asym, &out->truth_peak_a, why, sizeof why) != 0)
        goto fail;
    if (!snapped) {
        snprintf(why, sizeof why, "the twin does not snap before protocol.shear_max");
        goto fail;
    }
    if (predict(sc, &snapped, &out->scene_dw, &out->scene_asym, NULL, why, sizeof why) != 0) goto fail;
    if (!snapped) {
        snprintf(why, sizeof why, "the scene does not snap before protocol.shear_max");
        goto fail;
    }
    family_film_opts fo = o->film;
    fo.dw_stop = o->shear_frac * out->truth_dw;
    fo.seed = o->film.seed + 7919u * (uint64_t)index;
    family_film film;
    if (family_film_run(&out->twin, &fo, &film, why, sizeof why) != 0) goto fail;
    out->film_stats = film;
    out->film_stats.obs = NULL;
    out->film_stats.true_dz = out->film_stats.true_a = NULL;
    out->film_stats.true_shapes = out->film_stats.tracked_shapes = NULL;
    int nb = 0;
    while (nb < film.n && film.obs[nb].dw == 0.0) nb++;
    rod_fit_opts fo_fit = o->fit;
    rod_scene fsc = *sc;
    if (o->held_at_truth) {
        /* Diagnostic: the parameters the fit holds are known exactly (the twin's). */
        double us[ROD_FIT_NKEYS], ut[ROD_FIT_NKEYS];
        rod_fit_scene_values(sc, us);
        rod_fit_scene_values(&out->twin, ut);
        for (int k = 0; k < ROD_FIT_NKEYS; k++)
            if (!fo_fit.fit[k]) us[k] = ut[k];
        rod_fit_scene_apply(&fsc, us);
        sc = &fsc;
    }
    if (o->noise_from_hold) hold_noise(&out->twin, film.obs, film.n, &fo_fit);
    out->shape_rms = film.shape_rms;
    if (o->shape_source == FAMILY_SHAPES_TRUTH) {
        /* The twin's own centreline with Gaussian noise of shape_noise per coordinate, from
           (seed, index) alone (a splitmix64 stream, Box-Muller). */
        uint64_t st = o->film.seed * 0x9E3779B97F4A7C15ull + 104729u * (uint64_t)index + 1u;
        for (int i = 0; i < film.nshapes; i++)
            for (int p = 0; p < 2 * film.true_shapes[i].k; p++) {
                double u[2];
                for (int q = 0; q < 2; q++) {
                    uint64_t z = (st += 0x9E3779B97F4A7C15ull);
                    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
                    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
                    z ^= z >> 31;
                    u[q] = ((double)(z >> 11) + 0.5) / 9007199254740992.0;
                }
                film.true_shapes[i].xz[p] += o->shape_noise * sqrt(-2.0 * log(u[0])) * cos(2.0 * M_PI * u[1]);
            }
        fo_fit.shapes = film.true_shapes;
        fo_fit.nshapes = film.nshapes;
    } else if (o->shape_source == FAMILY_SHAPES_TRACKER) {
        fo_fit.shapes = film.tracked_shapes;
        fo_fit.nshapes = film.nshapes;
    }
    out->nshapes = fo_fit.nshapes;
    out->sigma_dz = fo_fit.sigma_dz;
    out->sigma_a = fo_fit.sigma_a;
    calibrate(sc, film.obs, nb, &fo_fit, &out->before);
    /* With the shear: a refresh as the runner makes it, started from the before-shear fit's
       values within the same bounds (the scene's own strip may have no upper state as far as the
       twin's 80%: 25% early for some twins). Without a before-shear fit, from the scene. */
    if (out->before.ok) {
        rod_scene warm = *sc;
        double centre[ROD_FIT_NKEYS];
        int carried = 0;
        if (!o->refresh_shapes) {
            /* The trial's refresh, by its rule (sim/rod_fit_carry.h, daemon/trial/trial_calibrate.c):
               without the centrelines, the positions carried from the fit before the shear (its
               values and standard errors as their prior), the other priors on the scene's values. */
            fo_fit.shapes = NULL;
            fo_fit.nshapes = 0;
            if (fo_fit.fit[ROD_FIT_POSITION_LEFT] && fo_fit.fit[ROD_FIT_POSITION_RIGHT])
                carried = rod_fit_carry_positions(out->before.fit.u, out->before.fit.se, ROD_FIT_CARRY_FLOOR,
                                                  fo_fit.prior_sigma[ROD_FIT_POSITION_LEFT], &warm, &fo_fit, centre);
        }
        if (!carried) rod_fit_scene_apply(&warm, out->before.fit.u); /* every prior on the first fit's */
        for (int k = 0; k < ROD_FIT_NKEYS; k++)
            if (fo_fit.fit[k]) {
                fo_fit.lo[k] = out->before.fit.lo[k];
                fo_fit.hi[k] = out->before.fit.hi[k];
            }
        calibrate(&warm, film.obs, film.n, &fo_fit, &out->at);
    } else {
        calibrate(sc, film.obs, film.n, &fo_fit, &out->at);
    }
    family_film_free(&film);
    out->ok = 1;
    out->wall_s = now_s() - t0;
    return 0;
fail:
    snprintf(out->why, sizeof out->why, "twin %d: %.230s", index, why);
    out->wall_s = now_s() - t0;
    return 0;
}
