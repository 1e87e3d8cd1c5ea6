/* family_summary.c: the family scored against issue 32 D's targets (family.h).
 *
 * Errors are |predicted - truth| / truth of the snap Delta W, truth the twin's own. A band is
 * the calibrated prediction's +- 2 sigma (rod_fit_snap's linearised sd). The regime is scored
 * only where the band does not reach the boundary, i.e. where the probability of the other
 * regime is below 2.3% (the one-sided 2-sigma tail); twins whose regime the fit leaves open are
 * counted as not scored, never as right. Medians of an even count are the mean of the middle two. */
#include "family.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define P_OTHER_SCORED 0.023

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    if (n <= 0) return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static double maxof(const double *v, int n)
{
    double m = n > 0 ? v[0] : NAN;
    for (int k = 1; k < n; k++) m = fmax(m, v[k]);
    return m;
}

/* One calibration kind over the family. */
static void score(const family_case *c, int n, int at, int *made, double *med, double *mx, double *in2,
                  double *zmed, int *scored, int *right)
{
    double *e = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    double *z = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    int m = 0, inside = 0;
    *scored = *right = 0;
    for (int k = 0; e && z && k < n; k++) {
        const family_fit *f = at ? &c[k].at : &c[k].before;
        if (!c[k].ok || !f->ok) continue;
        double d = fabs(f->snap.snap_dw - c[k].truth_dw);
        e[m] = d / c[k].truth_dw;
        z[m] = f->snap.snap_sd > 0 ? d / f->snap.snap_sd : INFINITY;
        if (f->snap.band_ok && d <= 2.0 * f->snap.snap_sd) inside++;
        m++;
        if (f->snap.band_ok && f->snap.p_other < P_OTHER_SCORED) {
            (*scored)++;
            if (f->snap.asymmetric == c[k].truth_asym) (*right)++;
        }
    }
    *made = m;
    *mx = maxof(e, m);
    *med = median(e, m);
    *zmed = median(z, m);
    *in2 = m > 0 ? (double)inside / m : NAN;
    free(e);
    free(z);
}

void family_summarise(const family_case *c, int n, family_summary *s)
{
    memset(s, 0, sizeof *s);
    s->twins = n;
    double *e = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    double *dz = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    double *a = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    double *sh = malloc(sizeof(double) * (size_t)(n > 0 ? n : 1));
    int m = 0, msh = 0;
    for (int k = 0; e && dz && a && sh && k < n; k++) {
        if (!c[k].ok) continue;
        e[m] = fabs(c[k].scene_dw - c[k].truth_dw) / c[k].truth_dw;
        dz[m] = c[k].film_stats.dz_rms;
        a[m] = c[k].film_stats.a_rms;
        m++;
        if (c[k].film_stats.nshapes > 0) sh[msh++] = c[k].film_stats.shape_rms;
        /* A fit that ran (its snap may not have) naming a fitted crease position not determined. */
        for (int at = 0; at < 2; at++) {
            const rod_fit_result *r = at ? &c[k].at.fit : &c[k].before.fit;
            int undet = 0;
            for (int p = ROD_FIT_POSITION_LEFT; p <= ROD_FIT_POSITION_RIGHT; p++)
                undet |= r->nfit > 0 && r->fitted[p] && !r->determined[p];
            *(at ? &s->at_pos_undetermined : &s->before_pos_undetermined) += undet;
        }
    }
    s->shape_rms = msh > 0 ? median(sh, msh) : -1.0;
    free(sh);
    s->ran = m;
    s->scene_max = maxof(e, m);
    s->scene_median = median(e, m);
    s->tracker_dz_rms = median(dz, m);
    s->tracker_a_rms = median(a, m);
    free(e);
    free(dz);
    free(a);
    score(c, n, 0, &s->fits_before, &s->before_median, &s->before_max, &s->before_in2sd, &s->before_z_median,
          &s->regime_scored_before, &s->regime_right_before);
    score(c, n, 1, &s->fits_at, &s->at_median, &s->at_max, &s->at_in2sd, &s->at_z_median, &s->regime_scored_at,
          &s->regime_right_at);
}
