/* rod_fit_joint.c: specimens fitted together with one hinge stiffness per unit width
 * (rod_fit_joint.h): each specimen's model is rod_fit.h's (followed path, sensitivities), the
 * joint Jacobian is assembled from their columns, and the fit, covariance and "not determined"
 * rules are rod_fit.c's over the joint parameter set. */
#include "rod_fit_joint.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_vector.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define FAIL_CAP 30 /* cap on failed model evaluations in one fit (as rod_fit.c) */

struct rod_fit_joint_model {
    int nspec, nown, np, nobs, nobs_max;
    int own[ROD_FIT_NKEYS];
    double kb_start;
    const rod_fit_joint_spec *specs;
    rod_fit_model **m;
    int *row0;                     /* first observation of each specimen in the joint order */
    double *ln_b;                  /* ln of each specimen's width */
    double (*u0)[ROD_FIT_NKEYS];   /* each scene's values */
    double *jac;                   /* one specimen's Jacobian, 2 nobs_max x ROD_FIT_NKEYS */
};

rod_fit_joint_opts rod_fit_joint_opts_default(void)
{
    rod_fit_joint_opts o;
    memset(&o, 0, sizeof o);
    o.each = rod_fit_opts_default();
    o.kb_lo = o.kb_hi = o.kb_start = NAN;
    o.kb_prior_sigma = INFINITY;
    return o;
}

/* The input checks of rod_fit_joint.h; the own keys into own[], their count returned (-1 refused). */
static int joint_check(const rod_fit_joint_spec *specs, int nspec, const rod_fit_joint_opts *o,
                       int own[ROD_FIT_NKEYS], char *why, size_t why_len)
{
    if (nspec < 1 || !specs) {
        snprintf(why, why_len, "a joint fit needs at least one specimen");
        return -1;
    }
    if (o->each.fit[ROD_FIT_HINGE]) {
        snprintf(why, why_len, "%s is the shared parameter of this fit (%s, k / b): it is not also fitted per "
                 "specimen", rod_fit_key_name(ROD_FIT_HINGE), ROD_FIT_JOINT_SHARED_KEY);
        return -1;
    }
    if (o->each.fit[ROD_FIT_HINGE_LEFT] || o->each.fit[ROD_FIT_HINGE_RIGHT]) {
        snprintf(why, why_len, "%s: one hinge per crease is not shared per unit width across specimens (which "
                 "crease of one specimen matches which of another is not known); the pair's hinge per unit width "
                 "(%s) is", rod_fit_key_name(o->each.fit[ROD_FIT_HINGE_LEFT] ? ROD_FIT_HINGE_LEFT : ROD_FIT_HINGE_RIGHT),
                 ROD_FIT_JOINT_SHARED_KEY);
        return -1;
    }
    if (!(o->kb_prior_sigma > 0.0)) {
        snprintf(why, why_len, "%s: the prior's width must be positive", ROD_FIT_JOINT_SHARED_KEY);
        return -1;
    }
    int n = 0;
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (o->each.fit[k]) own[n++] = k;
    for (int s = 0; s < nspec; s++) {
        const rod_fit_joint_spec *sp = &specs[s];
        const char *nm = sp->name && sp->name[0] ? sp->name : NULL;
        if (!nm || !sp->scene || !sp->obs) {
            snprintf(why, why_len, "specimen %d: %s", s + 1, !nm ? "no name" : "no scene or no observations");
            return -1;
        }
        for (int t = 0; t < s; t++)
            if (!strcmp(specs[t].name, nm)) {
                snprintf(why, why_len, "two specimens are named %s: their keys would be one", nm);
                return -1;
            }
        double b = sp->scene->width;
        if (!isfinite(b) || !(b > 0.0)) {
            snprintf(why, why_len, "specimen %s: its width is unknown (ribbon.width %g): the hinge stiffness per "
                     "unit width needs each specimen's width", nm, b);
            return -1;
        }
        char w[256];
        if (rod_fit_key_usable(sp->scene, ROD_FIT_HINGE, w, sizeof w)) {
            snprintf(why, why_len, "specimen %s: no hinge to share: %s", nm, w);
            return -1;
        }
        for (int i = 0; i < n; i++)
            if (rod_fit_key_usable(sp->scene, (rod_fit_key)own[i], w, sizeof w)) {
                snprintf(why, why_len, "specimen %s: %s", nm, w);
                return -1;
            }
    }
    return n;
}

void rod_fit_joint_model_free(rod_fit_joint_model *m)
{
    if (!m) return;
    if (m->m)
        for (int s = 0; s < m->nspec; s++) rod_fit_model_free(m->m[s]);
    free(m->m);
    free(m->row0);
    free(m->ln_b);
    free(m->u0);
    free(m->jac);
    free(m);
}

rod_status rod_fit_joint_model_alloc(const rod_fit_joint_spec *specs, int nspec, const rod_fit_joint_opts *o,
                                     rod_fit_joint_model **out, char *why, size_t why_len)
{
    *out = NULL;
    int own[ROD_FIT_NKEYS];
    int nown = joint_check(specs, nspec, o, own, why, why_len);
    if (nown < 0) return ROD_ERR_SCENE;
    rod_fit_joint_model *m = calloc(1, sizeof *m);
    if (!m) goto oom;
    m->nspec = nspec;
    m->nown = nown;
    m->np = 1 + nspec * nown;
    memcpy(m->own, own, sizeof own);
    m->specs = specs;
    m->m = calloc((size_t)nspec, sizeof *m->m);
    m->row0 = calloc((size_t)nspec, sizeof *m->row0);
    m->ln_b = calloc((size_t)nspec, sizeof *m->ln_b);
    m->u0 = calloc((size_t)nspec, sizeof *m->u0);
    if (!m->m || !m->row0 || !m->ln_b || !m->u0) goto oom;
    double kb = 0.0;
    for (int s = 0; s < nspec; s++) {
        m->row0[s] = m->nobs;
        m->nobs += specs[s].nobs;
        if (specs[s].nobs > m->nobs_max) m->nobs_max = specs[s].nobs;
        m->ln_b[s] = log(specs[s].scene->width);
        rod_fit_scene_values(specs[s].scene, m->u0[s]);
        kb += m->u0[s][ROD_FIT_HINGE] - m->ln_b[s];
        char w[256];
        rod_status st = rod_fit_model_alloc(specs[s].scene, specs[s].obs, specs[s].nobs, o->each.paper, &m->m[s], w,
                                            sizeof w);
        if (st != ROD_OK) {
            snprintf(why, why_len, "specimen %s: %s", specs[s].name, w);
            rod_fit_joint_model_free(m);
            return st;
        }
    }
    m->kb_start = isnan(o->kb_start) ? kb / nspec : o->kb_start;
    m->jac = malloc(sizeof(double) * 2 * (size_t)(m->nobs_max > 0 ? m->nobs_max : 1) * ROD_FIT_NKEYS);
    if (!m->jac) goto oom;
    *out = m;
    return ROD_OK;
oom:
    rod_fit_joint_model_free(m);
    snprintf(why, why_len, "out of memory");
    return ROD_ERR_ALLOC;
}

int rod_fit_joint_model_np(const rod_fit_joint_model *m)
{
    return m->np;
}

int rod_fit_joint_model_nobs(const rod_fit_joint_model *m)
{
    return m->nobs;
}

void rod_fit_joint_model_start(const rod_fit_joint_model *m, double *theta)
{
    theta[0] = m->kb_start;
    for (int s = 0; s < m->nspec; s++)
        for (int i = 0; i < m->nown; i++) theta[1 + s * m->nown + i] = m->u0[s][m->own[i]];
}

void rod_fit_joint_model_reset(rod_fit_joint_model *m)
{
    for (int s = 0; s < m->nspec; s++) rod_fit_model_reset(m->m[s]);
}

/* Specimen s's parameters at theta. */
static void spec_u(const rod_fit_joint_model *m, int s, const double *theta, double u[ROD_FIT_NKEYS])
{
    memcpy(u, m->u0[s], sizeof(double) * ROD_FIT_NKEYS);
    u[ROD_FIT_HINGE] = theta[0] + m->ln_b[s];
    for (int i = 0; i < m->nown; i++) u[m->own[i]] = theta[1 + s * m->nown + i];
}

rod_status rod_fit_joint_model_eval(rod_fit_joint_model *m, const double *theta, double *y, double *J, char *why,
                                    size_t why_len)
{
    int np = m->np;
    for (int s = 0; s < m->nspec; s++) {
        double u[ROD_FIT_NKEYS];
        int use[ROD_FIT_NKEYS] = {0};
        spec_u(m, s, theta, u);
        use[ROD_FIT_HINGE] = 1;
        for (int i = 0; i < m->nown; i++) use[m->own[i]] = 1;
        char w[384];
        rod_status st = rod_fit_model_eval(m->m[s], u, use, y + 2 * m->row0[s], J ? m->jac : NULL, w, sizeof w);
        if (st != ROD_OK) {
            snprintf(why, why_len, "specimen %s: %s", m->specs[s].name, w);
            return st;
        }
        if (!J) continue;
        /* Specimen s's rows: the shared column (d ln k_s / d ln(k / b) = 1) and its own columns;
           every other specimen's columns are zero. */
        for (int r = 0; r < 2 * m->specs[s].nobs; r++) {
            double *row = J + (size_t)(2 * m->row0[s] + r) * (size_t)np;
            memset(row, 0, sizeof(double) * (size_t)np);
            row[0] = m->jac[r * ROD_FIT_NKEYS + ROD_FIT_HINGE];
            for (int i = 0; i < m->nown; i++) row[1 + s * m->nown + i] = m->jac[r * ROD_FIT_NKEYS + m->own[i]];
        }
    }
    return ROD_OK;
}

/* ---- the fit ---- */

typedef struct jctx {
    rod_fit_joint_model *m;
    const rod_fit_joint_opts *o;
    int np, nres, ndata;
    double *th0, *lo, *hi, *scale, *prior; /* per joint parameter, fit units */
    double *obs, *w;                       /* observed value and weight of each data row */
    double *y, *J;                         /* model at the last evaluation */
    double *last_f, *cache_x, *cache_J;
    int cached, evaluations, failures, cancelled;
    char why[512];
} jctx;

static void x_to_theta(const jctx *c, const gsl_vector *x, double *th)
{
    for (int i = 0; i < c->np; i++)
        th[i] = fmin(c->hi[i], fmax(c->lo[i], c->th0[i] + c->scale[i] * gsl_vector_get(x, (size_t)i)));
}

static int eval_fj(const gsl_vector *x, jctx *c, gsl_vector *f, gsl_matrix *Jm)
{
    int np = c->np;
    double *th = c->cache_x + np; /* scratch after the cached x */
    x_to_theta(c, x, th);
    if (c->o->each.cancel && atomic_load(c->o->each.cancel)) {
        c->cancelled = 1;
        return GSL_EBADFUNC;
    }
    c->evaluations++;
    char why[512];
    rod_status st = rod_fit_joint_model_eval(c->m, th, c->y, c->J, why, sizeof why);
    if (st != ROD_OK) {
        c->failures++;
        snprintf(c->why, sizeof c->why, "%s", why);
        for (int i = 0; i < c->nres; i++)
            if (f) gsl_vector_set(f, (size_t)i, 1e3 * (fabs(c->last_f[i]) + 1.0));
        if (Jm) gsl_matrix_set_zero(Jm);
        c->cached = 0;
        return GSL_SUCCESS;
    }
    for (int r = 0; r < c->ndata; r++) {
        c->last_f[r] = (c->y[r] - c->obs[r]) * c->w[r];
        for (int i = 0; i < np; i++) c->cache_J[(size_t)r * np + i] = c->J[(size_t)r * np + i] * c->w[r] * c->scale[i];
    }
    int row = c->ndata;
    for (int i = 0; i < np; i++) {
        if (!isfinite(c->prior[i])) continue;
        c->last_f[row] = (th[i] - c->th0[i]) / c->prior[i];
        for (int ii = 0; ii < np; ii++) c->cache_J[(size_t)row * np + ii] = ii == i ? c->scale[i] / c->prior[i] : 0.0;
        row++;
    }
    for (int i = 0; i < np; i++) c->cache_x[i] = gsl_vector_get(x, (size_t)i);
    c->cached = 1;
    for (int i = 0; i < c->nres; i++) {
        if (f) gsl_vector_set(f, (size_t)i, c->last_f[i]);
        if (Jm)
            for (int j = 0; j < np; j++) gsl_matrix_set(Jm, (size_t)i, (size_t)j, c->cache_J[(size_t)i * np + j]);
    }
    return GSL_SUCCESS;
}

static int cb_f(const gsl_vector *x, void *p, gsl_vector *f)
{
    jctx *c = p;
    if (c->failures > FAIL_CAP) return GSL_EMAXITER;
    return eval_fj(x, c, f, NULL);
}

static int cb_df(const gsl_vector *x, void *p, gsl_matrix *J)
{
    jctx *c = p;
    int same = c->cached;
    for (int i = 0; same && i < c->np; i++) same = c->cache_x[i] == gsl_vector_get(x, (size_t)i);
    if (!same) return eval_fj(x, c, NULL, J);
    for (int i = 0; i < c->nres; i++)
        for (int j = 0; j < c->np; j++) gsl_matrix_set(J, (size_t)i, (size_t)j, c->cache_J[(size_t)i * c->np + j]);
    return GSL_SUCCESS;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* rod_fit.c's default bounds of an own key. */
static void default_bounds(int k, double u0, double *lo, double *hi)
{
    switch (k) {
    case ROD_FIT_ANGLE_LEFT:
    case ROD_FIT_ANGLE_RIGHT: *lo = u0 - 20.0; *hi = u0 + 20.0; break;
    case ROD_FIT_POSITION_LEFT:
    case ROD_FIT_POSITION_RIGHT: *lo = fmax(u0 - 0.05, 1e-3); *hi = fmin(u0 + 0.05, 1.0 - 1e-3); break;
    case ROD_FIT_DZ_OFFSET: *lo = u0 - 0.05; *hi = u0 + 0.05; break;
    default: *lo = u0 - log(10.0); *hi = u0 + log(10.0); break;
    }
}

/* Covariance, standard errors, correlations and the undetermined parameters (rod_fit.c's rules)
   from the weighted, scaled Jacobian Jw (nres x np, data rows first) at the solution. */
static int covariance(jctx *c, rod_fit_joint_result *res)
{
    int n = c->nres, p = c->np, nd = c->ndata;
    const double *Jw = c->cache_J;
    gsl_matrix *A = gsl_matrix_alloc((size_t)(n > p ? n : p), (size_t)p);
    gsl_matrix *V = gsl_matrix_alloc((size_t)p, (size_t)p);
    gsl_vector *S = gsl_vector_alloc((size_t)p), *work = gsl_vector_alloc((size_t)p);
    int *bad = calloc((size_t)p, sizeof *bad);
    int rc = -1;
    if (!A || !V || !S || !work || !bad) goto done;
    gsl_matrix_set_zero(A);
    for (int i = 0; i < nd; i++)
        for (int j = 0; j < p; j++)
            gsl_matrix_set(A, (size_t)i, (size_t)j, Jw[(size_t)i * p + j] * (c->hi[j] - c->lo[j]) / c->scale[j]);
    gsl_linalg_SV_decomp(A, V, S, work);
    res->sv_max = gsl_vector_get(S, 0);
    res->sv_min = gsl_vector_get(S, (size_t)p - 1);
    for (int d = 0; d < p; d++) {
        if (gsl_vector_get(S, (size_t)d) >= 1.0) continue;
        for (int j = 0; j < p; j++)
            if (fabs(gsl_matrix_get(V, (size_t)j, (size_t)d)) > 0.3) bad[j] = 1;
    }
    gsl_matrix_set_zero(A);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < p; j++) gsl_matrix_set(A, (size_t)i, (size_t)j, Jw[(size_t)i * p + j]);
    gsl_linalg_SV_decomp(A, V, S, work);
    double smax = gsl_vector_get(S, 0);
    double factor = 1.0;
    if (c->o->each.scale_covariance && nd > p) factor = res->chi2 / (double)(nd - p);
    res->cov_scaled = factor != 1.0;
    for (int a = 0; a < p; a++)
        for (int b = 0; b < p; b++) {
            double s = 0.0;
            for (int d = 0; d < p; d++) {
                double sv = gsl_vector_get(S, (size_t)d);
                if (!(sv > 1e-12 * smax)) continue;
                s += gsl_matrix_get(V, (size_t)a, (size_t)d) * gsl_matrix_get(V, (size_t)b, (size_t)d) / (sv * sv);
            }
            res->cov[(size_t)a * p + b] = factor * s * c->scale[a] * c->scale[b];
        }
    for (int a = 0; a < p; a++) {
        double v = res->cov[(size_t)a * p + a];
        if (!(sqrt(v) <= c->hi[a] - c->lo[a])) bad[a] = 1;
        res->determined[a] = !bad[a];
        res->se[a] = (bad[a] && !isfinite(c->prior[a])) ? INFINITY : sqrt(v);
    }
    for (int a = 0; a < p; a++)
        for (int b = 0; b < p; b++) {
            double d = sqrt(res->cov[(size_t)a * p + a] * res->cov[(size_t)b * p + b]);
            res->corr[(size_t)a * p + b] =
                (res->determined[a] && res->determined[b] && d > 0.0) ? res->cov[(size_t)a * p + b] / d : 0.0;
        }
    for (int a = 0; a < p; a++)
        if (!res->determined[a] && !isfinite(res->se[a]))
            for (int b = 0; b < p; b++) res->cov[(size_t)a * p + b] = res->cov[(size_t)b * p + a] = 0.0;
    rc = 0;
done:
    gsl_matrix_free(A);
    gsl_matrix_free(V);
    gsl_vector_free(S);
    gsl_vector_free(work);
    free(bad);
    return rc;
}

void rod_fit_joint_result_free(rod_fit_joint_result *res)
{
    free(res->spec);
    free(res->key);
    free(res->cov);
    free(res->corr);
    free(res->se);
    free(res->determined);
    memset(res, 0, sizeof *res);
}

/* Each specimen's view of the joint result (rod_fit_joint.h). */
static void spec_results(const jctx *c, const double *th, rod_fit_joint_result *res)
{
    const rod_fit_joint_model *m = c->m;
    int p = c->np;
    for (int s = 0; s < m->nspec; s++) {
        rod_fit_result *r = &res->spec[s];
        int idx[ROD_FIT_NKEYS], key[ROD_FIT_NKEYS], q = 0;
        memcpy(r->u0, m->u0[s], sizeof r->u0);
        spec_u(m, s, th, r->u);
        idx[q] = 0;
        key[q++] = ROD_FIT_HINGE;
        for (int i = 0; i < m->nown; i++) {
            idx[q] = 1 + s * m->nown + i;
            key[q++] = m->own[i];
        }
        for (int a = 0; a < q; a++) {
            int k = key[a], i = idx[a];
            double off = k == ROD_FIT_HINGE ? m->ln_b[s] : 0.0;
            r->fitted[k] = 1;
            r->lo[k] = c->lo[i] + off;
            r->hi[k] = c->hi[i] + off;
            r->se[k] = res->se[i];
            r->determined[k] = res->determined[i];
            double tol = 1e-9 * (c->hi[i] - c->lo[i]);
            r->at_bound[k] = th[i] <= c->lo[i] + tol ? -1 : th[i] >= c->hi[i] - tol ? 1 : 0;
            for (int b = 0; b < q; b++) {
                r->cov[k][key[b]] = res->cov[(size_t)i * p + idx[b]];
                r->corr[k][key[b]] = res->corr[(size_t)i * p + idx[b]];
            }
        }
        r->nobs = m->specs[s].nobs;
        r->nres = 2 * r->nobs;
        r->nfit = q;
        double chi2 = 0.0;
        for (int row = 2 * m->row0[s]; row < 2 * (m->row0[s] + r->nobs); row++) chi2 += c->last_f[row] * c->last_f[row];
        r->chi2 = chi2;
        r->rms = r->nobs ? sqrt(chi2 / r->nres) : 0.0;
        r->misfit = r->rms > c->o->each.misfit;
        r->iterations = res->iterations;
        r->evaluations = res->evaluations;
        r->capped = res->capped;
        r->cov_scaled = res->cov_scaled;
        r->sv_min = res->sv_min;
        r->sv_max = res->sv_max;
    }
}

static rod_status joint_alloc_result(rod_fit_joint_result *res, int nspec, int np)
{
    res->spec = calloc((size_t)nspec, sizeof *res->spec);
    res->key = calloc((size_t)np, sizeof *res->key);
    res->cov = calloc((size_t)np * np, sizeof *res->cov);
    res->corr = calloc((size_t)np * np, sizeof *res->corr);
    res->se = calloc((size_t)np, sizeof *res->se);
    res->determined = calloc((size_t)np, sizeof *res->determined);
    return res->spec && res->key && res->cov && res->corr && res->se && res->determined ? ROD_OK : ROD_ERR_ALLOC;
}

rod_status rod_fit_joint_run(const rod_fit_joint_spec *specs, int nspec, const rod_fit_joint_opts *o,
                             rod_fit_joint_result *res, char *why, size_t why_len)
{
    double t0 = now_s();
    memset(res, 0, sizeof *res);
    jctx c;
    memset(&c, 0, sizeof c);
    c.o = o;
    const rod_fit_opts *e = &o->each;
    gsl_vector *x = NULL;
    gsl_multifit_nlinear_workspace *w = NULL;
    rod_status st = rod_fit_joint_model_alloc(specs, nspec, o, &c.m, why, why_len);
    if (st != ROD_OK) return st;
    rod_fit_joint_model *m = c.m;
    int p = c.np = m->np;
    res->nspec = nspec;
    res->nown = m->nown;
    res->np = p;
    memcpy(res->own, m->own, sizeof res->own);
    if (!(e->sigma_dz > 0.0) || !(e->sigma_a > 0.0) || !isfinite(e->sigma_dz) || !isfinite(e->sigma_a)) {
        snprintf(why, why_len, "the noise of Delta Z and of A must be positive and finite");
        st = ROD_ERR_SCENE;
        goto done;
    }
    if ((st = joint_alloc_result(res, nspec, p)) != ROD_OK) goto oom;
    c.th0 = calloc((size_t)p, sizeof(double));
    c.lo = calloc((size_t)p, sizeof(double));
    c.hi = calloc((size_t)p, sizeof(double));
    c.scale = calloc((size_t)p, sizeof(double));
    c.prior = calloc((size_t)p, sizeof(double));
    if (!c.th0 || !c.lo || !c.hi || !c.scale || !c.prior) goto oom;
    rod_fit_joint_model_start(m, c.th0);
    /* The shared parameter. */
    c.lo[0] = isnan(o->kb_lo) ? c.th0[0] - log(100.0) : o->kb_lo;
    c.hi[0] = isnan(o->kb_hi) ? c.th0[0] + log(100.0) : o->kb_hi;
    c.scale[0] = 1.0;
    c.prior[0] = o->kb_prior_sigma;
    snprintf(res->key[0], sizeof res->key[0], "%s", ROD_FIT_JOINT_SHARED_KEY);
    if (!(c.lo[0] < c.hi[0]) || !(c.lo[0] <= c.th0[0] && c.th0[0] <= c.hi[0])) {
        snprintf(why, why_len, "%s: the bounds [%g, %g] N/rad do not hold the start %g N/rad", ROD_FIT_JOINT_SHARED_KEY,
                 exp(c.lo[0]), exp(c.hi[0]), exp(c.th0[0]));
        st = ROD_ERR_SCENE;
        goto done;
    }
    for (int s = 0; s < nspec; s++)
        for (int i = 0; i < m->nown; i++) {
            int j = 1 + s * m->nown + i, k = m->own[i];
            double lo, hi;
            default_bounds(k, c.th0[j], &lo, &hi);
            if (!isnan(e->lo[k])) lo = e->lo[k];
            if (!isnan(e->hi[k])) hi = e->hi[k];
            snprintf(res->key[j], sizeof res->key[j], "%s:%s", specs[s].name, rod_fit_key_name((rod_fit_key)k));
            if (!(lo < hi) || !(lo <= c.th0[j] && c.th0[j] <= hi)) {
                snprintf(why, why_len, "%s: the bounds [%g, %g] do not hold the scene's value %g", res->key[j], lo, hi,
                         c.th0[j]);
                st = ROD_ERR_SCENE;
                goto done;
            }
            if (!(e->prior_sigma[k] > 0.0)) {
                snprintf(why, why_len, "%s: the prior's width must be positive", res->key[j]);
                st = ROD_ERR_SCENE;
                goto done;
            }
            c.lo[j] = lo;
            c.hi[j] = hi;
            c.scale[j] = (k == ROD_FIT_POSITION_LEFT || k == ROD_FIT_POSITION_RIGHT || k == ROD_FIT_DZ_OFFSET) ? 0.01 : 1.0;
            c.prior[j] = e->prior_sigma[k];
        }
    for (int s = 0; s < nspec; s++) {
        int need = e->min_obs > 2 + m->nown ? e->min_obs : 2 + m->nown; /* own keys, the shared one, plus one */
        if (specs[s].nobs < need) {
            snprintf(why, why_len, "specimen %s: too few observations: %d (at least %d needed)", specs[s].name,
                     specs[s].nobs, need);
            st = ROD_ERR_SCENE;
            goto done;
        }
        for (int k = 0; k < specs[s].nobs; k++) {
            const rod_fit_obs *ob = &specs[s].obs[k];
            if (!isfinite(ob->dl) || !isfinite(ob->dw) || !isfinite(ob->dz) || !isfinite(ob->a) || ob->dl <= 0.0 ||
                ob->dl >= 1.0) {
                snprintf(why, why_len, "specimen %s, observation %d: Delta L must be in (0, 1) and every value finite",
                         specs[s].name, k + 1);
                st = ROD_ERR_SCENE;
                goto done;
            }
        }
    }
    c.ndata = 2 * m->nobs;
    int npri = 0;
    for (int i = 0; i < p; i++) npri += isfinite(c.prior[i]);
    c.nres = c.ndata + npri;
    res->nobs = m->nobs;
    res->nres = c.ndata;
    res->kb0 = c.th0[0];
    res->kb_lo = c.lo[0];
    res->kb_hi = c.hi[0];
    c.obs = malloc(sizeof(double) * (size_t)c.ndata);
    c.w = malloc(sizeof(double) * (size_t)c.ndata);
    c.y = malloc(sizeof(double) * (size_t)c.ndata);
    c.J = malloc(sizeof(double) * (size_t)c.ndata * (size_t)p);
    c.last_f = calloc((size_t)c.nres, sizeof(double));
    c.cache_x = calloc(2 * (size_t)p, sizeof(double));
    c.cache_J = calloc((size_t)c.nres * (size_t)p, sizeof(double));
    x = gsl_vector_calloc((size_t)p);
    if (!c.obs || !c.w || !c.y || !c.J || !c.last_f || !c.cache_x || !c.cache_J || !x) goto oom;
    for (int s = 0; s < nspec; s++)
        for (int k = 0; k < specs[s].nobs; k++) {
            int r = 2 * (m->row0[s] + k);
            c.obs[r] = specs[s].obs[k].dz;
            c.obs[r + 1] = specs[s].obs[k].a;
            c.w[r] = 1.0 / e->sigma_dz;
            c.w[r + 1] = 1.0 / e->sigma_a;
        }
    if (eval_fj(x, &c, NULL, NULL) != GSL_SUCCESS || c.failures) {
        if (c.cancelled) goto cancelled;
        snprintf(why, why_len, "the specimens' own strips at the start: %s", c.why);
        st = ROD_ERR_BRANCH_LOST;
        goto done;
    }
    {
        double s2 = 0.0;
        for (int i = 0; i < c.ndata; i++) s2 += c.last_f[i] * c.last_f[i];
        res->rms_start = sqrt(s2 / c.ndata);
        for (int s = 0; s < nspec; s++) {
            double q = 0.0;
            for (int r = 2 * m->row0[s]; r < 2 * (m->row0[s] + specs[s].nobs); r++) q += c.last_f[r] * c.last_f[r];
            res->spec[s].rms_start = sqrt(q / (2.0 * specs[s].nobs));
        }
    }
    gsl_multifit_nlinear_parameters par = gsl_multifit_nlinear_default_parameters();
    par.trs = gsl_multifit_nlinear_trs_lm;
    w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &par, (size_t)c.nres, (size_t)p);
    if (!w) goto oom;
    gsl_multifit_nlinear_fdf fdf;
    memset(&fdf, 0, sizeof fdf);
    fdf.f = cb_f;
    fdf.df = cb_df;
    fdf.n = (size_t)c.nres;
    fdf.p = (size_t)p;
    fdf.params = &c;
    int info = 0;
    int gs = gsl_multifit_nlinear_init(x, &fdf, w);
    if (gs == GSL_SUCCESS)
        gs = gsl_multifit_nlinear_driver((size_t)e->max_iterations, 1e-8, 1e-10, 1e-10, NULL, NULL, &info, w);
    res->iterations = (int)gsl_multifit_nlinear_niter(w);
    if (c.cancelled) goto cancelled;
    if (c.failures > FAIL_CAP) {
        snprintf(why, why_len, "the model failed at %d trial parameter sets (last: %s)", c.failures, c.why);
        st = ROD_ERR_BRANCH_LOST;
        goto done;
    }
    res->capped = gs == GSL_EMAXITER;
    if (gs != GSL_SUCCESS && gs != GSL_EMAXITER && gs != GSL_ENOPROG) {
        snprintf(why, why_len, "Levenberg-Marquardt stopped: %s", gsl_strerror(gs));
        st = ROD_ERR_SINGULAR;
        goto done;
    }
    gsl_vector_memcpy(x, gsl_multifit_nlinear_position(w));
    int fails = c.failures;
    eval_fj(x, &c, NULL, NULL);
    if (c.failures != fails) {
        snprintf(why, why_len, "the fitted strips: %s", c.why);
        st = ROD_ERR_BRANCH_LOST;
        goto done;
    }
    double *th = c.cache_x + p;
    x_to_theta(&c, x, th);
    for (int i = 0; i < c.ndata; i++) res->chi2 += c.last_f[i] * c.last_f[i];
    res->rms = sqrt(res->chi2 / c.ndata);
    res->misfit = res->rms > e->misfit;
    if (covariance(&c, res)) goto oom;
    res->kb = th[0];
    res->kb_se = res->se[0];
    res->kb_determined = res->determined[0];
    {
        double tol = 1e-9 * (c.hi[0] - c.lo[0]);
        res->kb_at_bound = th[0] <= c.lo[0] + tol ? -1 : th[0] >= c.hi[0] - tol ? 1 : 0;
    }
    res->evaluations = c.evaluations;
    spec_results(&c, th, res);
    res->model_failures = c.failures;
    st = ROD_OK;
    goto done;
oom:
    snprintf(why, why_len, "out of memory");
    st = ROD_ERR_ALLOC;
    goto done;
cancelled:
    snprintf(why, why_len, "cancelled");
    st = ROD_ERR_TIME_LIMIT;
done:
    res->evaluations = c.evaluations;
    res->wall_s = now_s() - t0;
    gsl_multifit_nlinear_free(w);
    gsl_vector_free(x);
    free(c.th0);
    free(c.lo);
    free(c.hi);
    free(c.scale);
    free(c.prior);
    free(c.obs);
    free(c.w);
    free(c.y);
    free(c.J);
    free(c.last_f);
    free(c.cache_x);
    free(c.cache_J);
    rod_fit_joint_model_free(c.m);
    return st;
}
