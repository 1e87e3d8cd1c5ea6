/* rod_fit_joint.c: specimens fitted together with one hinge stiffness per unit width
 * (rod_fit_joint.h): each specimen's model is rod_fit.h's (followed path, sensitivities), the
 * joint Jacobian is assembled from their columns, and the fit, covariance and "not determined"
 * rules are rod_fit.c's over the joint parameter set. */
#include "rod_fit_joint.h"
#include "rod_fit_lm.h"
#include "rod_fit_sandwich.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>


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
    double *last_f, *cache_J;              /* last good residuals, their weighted Jacobian */
    double *th;                            /* scratch: the joint parameters at x */
    int evaluations, failures, cancelled;
    char why[512];
} jctx;

static void x_to_theta(const jctx *c, const double *x, double *th)
{
    for (int i = 0; i < c->np; i++) th[i] = fmin(c->hi[i], fmax(c->lo[i], c->th0[i] + c->scale[i] * x[i]));
}

/* The residuals and their Jacobian at x into last_f and cache_J: 0, 1 when a specimen's model
   failed there (kept, the reason in c->why), -1 when cancelled or past ROD_FIT_LM_FAIL_CAP failures. */
static int eval_point(void *user, const double *x)
{
    jctx *c = user;
    if (c->failures > ROD_FIT_LM_FAIL_CAP) return -1;
    int np = c->np;
    double *th = c->th;
    x_to_theta(c, x, th);
    if (c->o->each.cancel && atomic_load(c->o->each.cancel)) {
        c->cancelled = 1;
        return -1;
    }
    c->evaluations++;
    char why[512];
    rod_status st = rod_fit_joint_model_eval(c->m, th, c->y, c->J, why, sizeof why);
    if (st != ROD_OK) {
        c->failures++;
        snprintf(c->why, sizeof c->why, "%s", why);
        return 1;
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
    return 0;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Covariance, standard errors, correlations and the undetermined parameters from the weighted,
   scaled Jacobian (nres x np, data rows first) at the solution (rod_fit_lm.h: rod_fit.c's rules,
   the tracker's common mode per phase of each specimen's observations included). */
static int covariance(jctx *c, rod_fit_joint_result *res)
{
    const rod_fit_joint_model *m = c->m;
    const rod_fit_opts *e = &c->o->each;
    int p = c->np, nd = c->ndata;
    int *phase = malloc(sizeof *phase * (size_t)(m->nobs > 0 ? m->nobs : 1));
    if (!phase) return -1;
    for (int s = 0; s < m->nspec; s++) rod_fit_phases(m->specs[s].obs, m->specs[s].nobs, phase + m->row0[s]);
    double factor = 1.0;
    if (e->scale_covariance && nd > p) factor = res->chi2 / (double)(nd - p);
    res->cov_scaled = factor != 1.0;
    rod_fit_lm_cov_in in = {.p = p, .nres = c->nres, .nobs = m->nobs, .Jw = c->cache_J, .f = c->last_f, .lo = c->lo,
                            .hi = c->hi, .scale = c->scale, .prior = c->prior, .factor = factor, .phase = phase,
                            .sigma = {e->sigma_dz, e->sigma_a}, .sigma_b = {e->sigma_b_dz, e->sigma_b_a}};
    rod_fit_lm_cov_out out = {.cov = res->cov, .corr = res->corr, .se = res->se, .determined = res->determined};
    int rc = rod_fit_lm_covariance(&in, &out);
    free(phase);
    res->sv_min = out.sv_min;
    res->sv_max = out.sv_max;
    res->sigma_b[0] = out.sigma_b[0];
    res->sigma_b[1] = out.sigma_b[1];
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
        r->sigma_b[0] = res->sigma_b[0];
        r->sigma_b[1] = res->sigma_b[1];
        r->gn_sd = res->gn_sd;
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
    double *x = NULL;
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
            rod_fit_key_bounds((rod_fit_key)k, c.th0[j], &lo, &hi);
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
            c.scale[j] = rod_fit_key_scale((rod_fit_key)k);
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
    c.th = calloc((size_t)p, sizeof(double));
    c.cache_J = calloc((size_t)c.nres * (size_t)p, sizeof(double));
    x = calloc((size_t)p, sizeof(double)); /* the start */
    if (!c.obs || !c.w || !c.y || !c.J || !c.last_f || !c.th || !c.cache_J || !x) goto oom;
    for (int s = 0; s < nspec; s++)
        for (int k = 0; k < specs[s].nobs; k++) {
            int r = 2 * (m->row0[s] + k);
            c.obs[r] = specs[s].obs[k].dz;
            c.obs[r + 1] = specs[s].obs[k].a;
            c.w[r] = 1.0 / e->sigma_dz;
            c.w[r + 1] = 1.0 / e->sigma_a;
        }
    if (eval_point(&c, x)) {
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
    rod_fit_lm_problem pr = {.p = p, .nres = c.nres, .eval = eval_point, .last_f = c.last_f, .last_J = c.cache_J,
                             .user = &c};
    st = rod_fit_lm_drive(&pr, x, e->max_iterations, e->stop_sd, &res->iterations, &res->gn_sd, &res->capped, why,
                          why_len);
    if (c.cancelled) goto cancelled;
    if (c.failures > ROD_FIT_LM_FAIL_CAP) {
        snprintf(why, why_len, "the model failed at %d trial parameter sets (last: %s)", c.failures, c.why);
        st = ROD_ERR_BRANCH_LOST;
        goto done;
    }
    if (st != ROD_OK) goto done;
    /* The solution, evaluated again so residual, Jacobian and values belong together. */
    if (eval_point(&c, x)) {
        if (c.cancelled) goto cancelled;
        snprintf(why, why_len, "the fitted strips: %s", c.why);
        st = ROD_ERR_BRANCH_LOST;
        goto done;
    }
    const double *th = c.th;
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
    free(x);
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
    free(c.th);
    free(c.cache_J);
    rod_fit_joint_model_free(c.m);
    return st;
}
