/* rod_fit_lm.c: the Levenberg-Marquardt loop and the covariance both strip fits run
 * (rod_fit_lm.h); moved here from rod_fit.c, whose rules they are. */
#include "rod_fit_lm.h"
#include "rod_fit_sandwich.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_vector.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct lm_ctx {
    const rod_fit_lm_problem *pr;
    double *x, *f, *J;  /* scratch: the point asked for, its residuals and Jacobian */
    double *xc;         /* the point whose Jacobian J holds (cached = 1) */
    int cached;
} lm_ctx;

/* x into the scratch; 1 when it is the cached point. */
static int take_x(lm_ctx *c, const gsl_vector *x)
{
    int same = c->cached;
    for (int i = 0; i < c->pr->p; i++) {
        c->x[i] = gsl_vector_get(x, (size_t)i);
        same = same && c->x[i] == c->xc[i];
    }
    return same;
}

/* eval at the scratch point into f and J: GSL_SUCCESS, or GSL_EBADFUNC (stopped). */
static int eval_at(lm_ctx *c)
{
    const rod_fit_lm_problem *pr = c->pr;
    size_t n = (size_t)pr->nres, nJ = n * (size_t)pr->p;
    int rc = pr->eval(pr->user, c->x);
    if (rc < 0) return GSL_EBADFUNC;
    c->cached = rc == 0;
    if (rc > 0) {
        /* A step into parameters without an upper state: a cost far above the last one, so the
           trust region shrinks. */
        for (size_t i = 0; i < n; i++) c->f[i] = 1e3 * (fabs(pr->last_f[i]) + 1.0);
        memset(c->J, 0, sizeof(double) * nJ);
        return GSL_SUCCESS;
    }
    memcpy(c->f, pr->last_f, sizeof(double) * n);
    memcpy(c->J, pr->last_J, sizeof(double) * nJ);
    memcpy(c->xc, c->x, sizeof(double) * (size_t)pr->p);
    return GSL_SUCCESS;
}

static int cb_f(const gsl_vector *x, void *p, gsl_vector *f)
{
    lm_ctx *c = p;
    take_x(c, x);
    int st = eval_at(c);
    if (st != GSL_SUCCESS) return st;
    for (int i = 0; i < c->pr->nres; i++) gsl_vector_set(f, (size_t)i, c->f[i]);
    return GSL_SUCCESS;
}

static int cb_df(const gsl_vector *x, void *p, gsl_matrix *J)
{
    lm_ctx *c = p;
    if (!take_x(c, x)) {
        int st = eval_at(c);
        if (st != GSL_SUCCESS) return st;
    }
    int np = c->pr->p;
    for (int i = 0; i < c->pr->nres; i++)
        for (int j = 0; j < np; j++) gsl_matrix_set(J, (size_t)i, (size_t)j, c->J[(size_t)i * np + j]);
    return GSL_SUCCESS;
}

/* The Gauss-Newton step still to go from the solver's position, in standard deviations: with J
   and f the weighted Jacobian and residuals (priors' rows included), J^T J is the inverse of the
   covariance, so the step -(J^T J)^-1 J^T f has the length sqrt(f^T J (J^T J)^-1 J^T f) = |Q1^T f|
   in that metric (J = Q1 R1; with a rank-deficient J, Q1 spans more than J's range and the
   length is an upper bound). Whatever the trust region's damping does to the steps themselves.
   Negative when it cannot be computed. */
static double gauss_newton_sd(gsl_multifit_nlinear_workspace *w, gsl_matrix *qr, gsl_vector *tau, gsl_vector *qtf)
{
    gsl_matrix_memcpy(qr, gsl_multifit_nlinear_jac(w));
    gsl_vector_memcpy(qtf, gsl_multifit_nlinear_residual(w));
    if (gsl_linalg_QR_decomp(qr, tau) != GSL_SUCCESS || gsl_linalg_QR_QTvec(qr, tau, qtf) != GSL_SUCCESS) return -1.0;
    double s = 0.0;
    for (size_t i = 0; i < qr->size2; i++) s += gsl_vector_get(qtf, i) * gsl_vector_get(qtf, i);
    return isfinite(s) ? sqrt(s) : -1.0;
}

/* gsl_multifit_nlinear_driver's loop (GSL 2.7: its tolerances, its return codes) with one more
   stop: the Gauss-Newton step still to go below stop_sd standard deviations (rod_fit_opts).
   Each iteration costs a path of static solves and its sensitivities, and near the optimum the
   trust region rejects steps of thousandths of a standard deviation (measured on the family's
   twin 0: 14 iterations and 34 evaluations to GSL's tolerances, of which the last 4 iterations
   and 19 evaluations moved the values by less than 0.05 sd). *gn_sd: that step at the end (-1
   unknown). */
static int drive(gsl_multifit_nlinear_workspace *w, int maxiter, double stop_sd, double *gn_sd)
{
    size_t n = gsl_multifit_nlinear_jac(w)->size1, p = gsl_multifit_nlinear_jac(w)->size2;
    gsl_matrix *qr = gsl_matrix_alloc(n, p);
    gsl_vector *tau = gsl_vector_alloc(p), *qtf = gsl_vector_alloc(n);
    int status, info = 0, iter = 0;
    *gn_sd = -1.0;
    if (!qr || !tau || !qtf) {
        gsl_matrix_free(qr); gsl_vector_free(tau); gsl_vector_free(qtf);
        return GSL_ENOMEM;
    }
    do {
        status = gsl_multifit_nlinear_iterate(w);
        if (status == GSL_ENOPROG && iter == 0) {
            status = GSL_EMAXITER; /* no step reduced the cost: as GSL's driver */
            break;
        }
        ++iter;
        *gn_sd = gauss_newton_sd(w, qr, tau, qtf);
        if (*gn_sd >= 0.0 && *gn_sd < stop_sd) {
            status = GSL_SUCCESS;
            break;
        }
        status = gsl_multifit_nlinear_test(1e-8, 1e-10, 1e-10, &info, w);
    } while (status == GSL_CONTINUE && iter < maxiter);
    if (status == GSL_ETOLF || status == GSL_ETOLX || status == GSL_ETOLG) status = GSL_SUCCESS;
    if (iter >= maxiter && status != GSL_SUCCESS) status = GSL_EMAXITER;
    gsl_matrix_free(qr); gsl_vector_free(tau); gsl_vector_free(qtf);
    return status;
}

rod_status rod_fit_lm_drive(const rod_fit_lm_problem *pr, double *x, int maxiter, double stop_sd, int *iterations,
                            double *gn_sd, int *capped, char *why, size_t why_len)
{
    size_t p = (size_t)pr->p, n = (size_t)pr->nres;
    lm_ctx c = {.pr = pr};
    *iterations = 0;
    *gn_sd = -1.0;
    *capped = 0;
    c.x = malloc(sizeof(double) * p);
    c.xc = malloc(sizeof(double) * p);
    c.f = malloc(sizeof(double) * n);
    c.J = malloc(sizeof(double) * n * p);
    gsl_vector *xv = gsl_vector_alloc(p);
    gsl_multifit_nlinear_parameters par = gsl_multifit_nlinear_default_parameters();
    par.trs = gsl_multifit_nlinear_trs_lm;
    gsl_multifit_nlinear_workspace *w = gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &par, n, p);
    int gs = GSL_ENOMEM;
    if (c.x && c.xc && c.f && c.J && xv && w) {
        gsl_multifit_nlinear_fdf fdf;
        memset(&fdf, 0, sizeof fdf);
        fdf.f = cb_f;
        fdf.df = cb_df;
        fdf.n = n;
        fdf.p = p;
        fdf.params = &c;
        for (size_t i = 0; i < p; i++) gsl_vector_set(xv, i, x[i]);
        gs = gsl_multifit_nlinear_init(xv, &fdf, w);
        if (gs == GSL_SUCCESS) gs = drive(w, maxiter, stop_sd, gn_sd);
        *iterations = (int)gsl_multifit_nlinear_niter(w);
        const gsl_vector *pos = gsl_multifit_nlinear_position(w);
        for (size_t i = 0; i < p; i++) x[i] = gsl_vector_get(pos, i);
    }
    gsl_multifit_nlinear_free(w);
    gsl_vector_free(xv);
    free(c.x);
    free(c.xc);
    free(c.f);
    free(c.J);
    *capped = gs == GSL_EMAXITER;
    /* GSL_ENOPROG: no step reduced the cost any more, the position is the best found. */
    if (gs == GSL_SUCCESS || gs == GSL_EMAXITER || gs == GSL_ENOPROG) return ROD_OK;
    if (gs == GSL_ENOMEM) {
        snprintf(why, why_len, "out of memory");
        return ROD_ERR_ALLOC;
    }
    if (gs == GSL_EBADFUNC) {
        snprintf(why, why_len, "stopped by its evaluation");
        return ROD_ERR_TIME_LIMIT;
    }
    snprintf(why, why_len, "Levenberg-Marquardt stopped: %s", gsl_strerror(gs));
    return ROD_ERR_SINGULAR;
}

/* The pseudo-inverse of J^T J from J's SVD in A (V, S): singular values below 1e-12 of the
   largest are left out. */
static void pinv_normal(const gsl_matrix *V, const gsl_vector *S, int p, double *hinv)
{
    double smax = gsl_vector_get(S, 0);
    for (int a = 0; a < p; a++)
        for (int b = 0; b < p; b++) {
            double s = 0.0;
            for (int d = 0; d < p; d++) {
                double sv = gsl_vector_get(S, (size_t)d);
                if (!(sv > 1e-12 * smax)) continue;
                s += gsl_matrix_get(V, (size_t)a, (size_t)d) * gsl_matrix_get(V, (size_t)b, (size_t)d) / (sv * sv);
            }
            hinv[(size_t)a * p + b] = s;
        }
}

int rod_fit_lm_covariance(const rod_fit_lm_cov_in *in, rod_fit_lm_cov_out *out)
{
    int n = in->nres, p = in->p, nd = 2 * in->nobs + in->nshape;
    size_t pp = (size_t)p * (size_t)p;
    gsl_matrix *A = gsl_matrix_alloc((size_t)(n > p ? n : p), (size_t)p);
    gsl_matrix *V = gsl_matrix_alloc((size_t)p, (size_t)p);
    gsl_vector *S = gsl_vector_alloc((size_t)p), *work = gsl_vector_alloc((size_t)p);
    int *bad = calloc((size_t)p, sizeof *bad);
    double *hinv = malloc(sizeof(double) * pp), *cw = malloc(sizeof(double) * pp);
    int rc = -1;
    if (!A || !V || !S || !work || !bad || !hinv || !cw) goto done;
    /* Data rows only, in units of each parameter's range: what the data determine. */
    gsl_matrix_set_zero(A);
    for (int i = 0; i < nd; i++)
        for (int j = 0; j < p; j++)
            gsl_matrix_set(A, (size_t)i, (size_t)j, in->Jw[(size_t)i * p + j] * (in->hi[j] - in->lo[j]) / in->scale[j]);
    gsl_linalg_SV_decomp(A, V, S, work);
    out->sv_max = gsl_vector_get(S, 0);
    out->sv_min = gsl_vector_get(S, (size_t)p - 1);
    for (int d = 0; d < p; d++) {
        if (gsl_vector_get(S, (size_t)d) >= 1.0) continue;
        for (int j = 0; j < p; j++)
            if (fabs(gsl_matrix_get(V, (size_t)j, (size_t)d)) > 0.3) bad[j] = 1;
    }
    /* The covariance with the priors, in x units. */
    gsl_matrix_set_zero(A);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < p; j++) gsl_matrix_set(A, (size_t)i, (size_t)j, in->Jw[(size_t)i * p + j]);
    gsl_linalg_SV_decomp(A, V, S, work);
    pinv_normal(V, S, p, hinv);
    memcpy(cw, hinv, sizeof(double) * pp);
    /* The tracker's per-phase common mode: the sandwich (rod_fit_sandwich.h). */
    double est[2], rho[2];
    rod_fit_common_mode_estimate(in->f, in->nobs, in->phase, est);
    for (int a = 0; a < 2; a++) {
        double sb = in->sigma_b[a], sg = in->sigma[a];
        rho[a] = sb > 0.0 ? (sb / sg) * (sb / sg) : sb < 0.0 ? est[a] : 0.0;
        out->sigma_b[a] = sqrt(rho[a]) * sg;
    }
    if (rod_fit_sandwich_add(in->Jw, in->nobs, p, in->phase, rho, hinv, cw)) goto done;
    if (in->nshapes > 0 && rod_fit_sandwich_add_shapes(in->Jw, in->f, p, 2 * in->nobs, in->shape_rows, in->nshapes, hinv, cw))
        goto done;
    for (int a = 0; a < p; a++)
        for (int b = 0; b < p; b++)
            out->cov[(size_t)a * p + b] = in->factor * cw[(size_t)a * p + b] * in->scale[a] * in->scale[b];
    for (int a = 0; a < p; a++) {
        double v = out->cov[(size_t)a * p + a];
        /* Also a standard error wider than the parameter's whole range. */
        if (!(sqrt(v) <= in->hi[a] - in->lo[a])) bad[a] = 1;
        out->determined[a] = !bad[a];
        out->se[a] = (bad[a] && !isfinite(in->prior[a])) ? INFINITY : sqrt(v);
    }
    for (int a = 0; a < p; a++)
        for (int b = 0; b < p; b++) {
            double d = sqrt(out->cov[(size_t)a * p + a] * out->cov[(size_t)b * p + b]);
            out->corr[(size_t)a * p + b] =
                (out->determined[a] && out->determined[b] && d > 0.0) ? out->cov[(size_t)a * p + b] / d : 0.0;
        }
    for (int a = 0; a < p; a++) /* nothing about an undetermined parameter is a number */
        if (!out->determined[a] && !isfinite(out->se[a]))
            for (int b = 0; b < p; b++) out->cov[(size_t)a * p + b] = out->cov[(size_t)b * p + a] = 0.0;
    rc = 0;
done:
    gsl_matrix_free(A);
    gsl_matrix_free(V);
    gsl_vector_free(S);
    gsl_vector_free(work);
    free(bad);
    free(hinv);
    free(cw);
    return rc;
}
