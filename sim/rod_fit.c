/* rod_fit.c: the strip fitted to observed equilibria: the model followed along the observed
 * states, Levenberg-Marquardt, covariance and unidentified directions (rod_fit.h). */
#include "rod_fit.h"
#include "rod_fit_lm.h"
#include "rod_fit_sandwich.h"

#include "rod_observe.h"
#include "rod_route.h"
#include "rod_sensitivity.h"
#include "rod_snapshot.h"
#include "rod_solver.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define STEP_MAX 0.02      /* largest step in Delta L or Delta W between static solves */
#define STEP_HALVINGS 8    /* a step halves at most this many times */
#define PATH_SOLVES 4000   /* cap on static solves per evaluation */

struct rod_fit_model {
    rod_scene sc;
    rod *r;
    rod_solver *s;
    rod_sens_ws *sens;
    rod_fit_base base;
    rod_newton_opts nopt;
    int nobs, paper;
    const rod_fit_obs *obs;
    int *order;              /* observation indices in path order */
    rod_snapshot *state;     /* last equilibrium of each (path order) */
    int *have;
    double *k1;
    /* Shapes (rod_fit_model_set_shapes): shape i is modelled at path position shape_at[i] (the
       first of its state's observations); its rows start at shape_row[i] of shape_y / shape_jac. */
    rod_fit_shape *shapes;
    int nshapes, shape_rows, shape_have_jac;
    int *shape_at, *shape_row;
    double *shape_y, *shape_jac;
    double *dq_buf, *save;       /* dq/du_j for every key (nfree each), scratch */
};

rod_fit_opts rod_fit_opts_default(void)
{
    rod_fit_opts o;
    memset(&o, 0, sizeof o);
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        o.lo[k] = o.hi[k] = NAN;
        o.prior_sigma[k] = INFINITY;
    }
    o.sigma_dz = 0.002;
    o.sigma_a = 0.015;
    o.sigma_shape = 0.001;
    o.max_iterations = 50;
    o.stop_sd = 0.05;
    o.min_obs = 3;
    o.misfit = 5.0;
    return o;
}

/* Path order: by Delta W, then Delta L, then as given (insertion sort: stable, no state). */
static void path_order(const rod_fit_obs *obs, int n, int *order)
{
    for (int k = 0; k < n; k++) {
        int v = order[k] = k, i = k;
        while (i > 0 && (obs[order[i - 1]].dw > obs[v].dw ||
                         (obs[order[i - 1]].dw == obs[v].dw && obs[order[i - 1]].dl > obs[v].dl))) {
            order[i] = order[i - 1];
            i--;
        }
        order[i] = v;
    }
}

void rod_fit_model_free(rod_fit_model *m)
{
    if (!m) return;
    if (m->state)
        for (int k = 0; k < m->nobs; k++) rod_snapshot_free(&m->state[k]);
    free(m->state);
    free(m->have);
    free(m->order);
    free(m->k1);
    free(m->shapes);
    free(m->shape_at);
    free(m->shape_row);
    free(m->shape_y);
    free(m->shape_jac);
    free(m->dq_buf);
    free(m->save);
    rod_sens_free(m->sens);
    rod_solver_free(m->s);
    rod_free(m->r);
    free(m);
}

void rod_fit_model_reset(rod_fit_model *m)
{
    memset(m->have, 0, sizeof(int) * (size_t)m->nobs);
}

rod_status rod_fit_model_alloc(const rod_scene *sc, const rod_fit_obs *obs, int nobs, int paper,
                               rod_fit_model **out, char *why, size_t why_len)
{
    *out = NULL;
    rod_fit_model *m = calloc(1, sizeof *m);
    if (!m) return ROD_ERR_ALLOC;
    m->sc = *sc;
    m->obs = obs;
    m->nobs = nobs;
    m->paper = paper;
    rod_status st = rod_alloc(sc, &m->r, why, why_len);
    if (st != ROD_OK) {
        free(m);
        return st;
    }
    m->s = rod_solver_alloc(m->r);
    m->sens = rod_sens_alloc(m->r);
    m->order = malloc(sizeof(int) * (size_t)nobs);
    m->state = calloc((size_t)nobs, sizeof *m->state);
    m->have = calloc((size_t)nobs, sizeof(int));
    m->k1 = malloc(sizeof(double) * (size_t)m->r->n);
    if (!m->s || !m->sens || !m->order || !m->state || !m->have || !m->k1) goto oom;
    for (int k = 0; k < nobs; k++)
        if (!rod_snapshot_alloc(m->r, &m->state[k])) goto oom;
    path_order(obs, nobs, m->order);
    rod_fit_base_init(&m->base, m->r, sc);
    m->nopt = rod_newton_opts_static(sc);
    m->nopt.positive_definite = 1; /* the upper states are stable: minimise */
    *out = m;
    return ROD_OK;
oom:
    rod_fit_model_free(m);
    snprintf(why, why_len, "out of memory");
    return ROD_ERR_ALLOC;
}

/* Newton at the current state with the clamps at (dl, dw); the state must stay on the upper
   branch (Delta Z > 0). */
static rod_status solve_at(rod_fit_model *m, double dl, double dw)
{
    rod_set_clamps(m->r, dl, dw);
    rod_frames_update(m->r);
    rod_newton_report rep;
    rod_status st = rod_newton_solve(m->r, m->s, &m->nopt, &rep);
    if (st != ROD_OK) return st;
    rod_obs o;
    rod_observe(m->r, m->k1, &o);
    if (!(o.dz > 0.0)) return ROD_ERR_BRANCH_LOST;
    return ROD_OK;
}

/* From the equilibrium in the rod at (dl0, dw0) to (dl1, dw1) by static solves, steps halved on
   failure. */
static rod_status step_to(rod_fit_model *m, rod_snapshot *tmp, double dl0, double dw0, double dl1, double dw1,
                          int *solves)
{
    double t = 0.0;
    double span = fmax(fabs(dl1 - dl0), fabs(dw1 - dw0));
    double dt = span > STEP_MAX ? STEP_MAX / span : 1.0;
    int halvings = 0;
    rod_status last = ROD_OK;
    if (span == 0.0) return solve_at(m, dl1, dw1);
    while (t < 1.0) {
        double tn = fmin(1.0, t + dt);
        rod_snapshot_save(m->r, tmp);
        if (++*solves > PATH_SOLVES) return ROD_ERR_ROUTE_CAP;
        last = solve_at(m, dl0 + tn * (dl1 - dl0), dw0 + tn * (dw1 - dw0));
        if (last == ROD_OK) {
            t = tn;
            continue;
        }
        rod_snapshot_load(m->r, tmp);
        if (++halvings > STEP_HALVINGS) return last;
        dt *= 0.5;
    }
    return ROD_OK;
}

/* 1 when two observations put the clamps at the same place (path order keeps such states next
   to each other). */
static int same_state(const rod_fit_obs *a, const rod_fit_obs *b)
{
    return a->dl == b->dl && a->dw == b->dw;
}

/* Observation `to`'s model values (and Jacobian rows) are observation `from`'s. */
static void copy_rows(int from, int to, double *y, double *jac)
{
    y[2 * to] = y[2 * from];
    y[2 * to + 1] = y[2 * from + 1];
    if (jac)
        memcpy(&jac[2 * to * ROD_FIT_NKEYS], &jac[2 * from * ROD_FIT_NKEYS], sizeof(double) * 2 * ROD_FIT_NKEYS);
}

rod_status rod_fit_model_set_shapes(rod_fit_model *m, const rod_fit_shape *shapes, int n, char *why,
                                    size_t why_len)
{
    free(m->shapes);
    free(m->shape_at);
    free(m->shape_row);
    free(m->shape_y);
    free(m->shape_jac);
    m->shapes = NULL;
    m->shape_at = m->shape_row = NULL;
    m->shape_y = m->shape_jac = NULL;
    m->nshapes = m->shape_rows = m->shape_have_jac = 0;
    if (n <= 0) return ROD_OK;
    int rows = 0;
    for (int i = 0; i < n; i++) {
        if (shapes[i].k < 1 || shapes[i].k > ROD_SHAPE_MAX_POINTS) {
            snprintf(why, why_len, "shape %d: %d points (1 to %d)", i + 1, shapes[i].k, ROD_SHAPE_MAX_POINTS);
            return ROD_ERR_SCENE;
        }
        for (int p = 0; p < 2 * shapes[i].k; p++)
            if (!isfinite(shapes[i].xz[p])) {
                snprintf(why, why_len, "shape %d: a point is not finite", i + 1);
                return ROD_ERR_SCENE;
            }
        rows += 2 * shapes[i].k;
    }
    int nf = rod_nfree(m->r);
    m->shapes = malloc(sizeof *m->shapes * (size_t)n);
    m->shape_at = malloc(sizeof(int) * (size_t)n);
    m->shape_row = malloc(sizeof(int) * (size_t)n);
    m->shape_y = calloc((size_t)rows, sizeof(double));
    m->shape_jac = calloc((size_t)rows * ROD_FIT_NKEYS, sizeof(double));
    if (!m->dq_buf) m->dq_buf = malloc(sizeof(double) * (size_t)nf * ROD_FIT_NKEYS);
    if (!m->save) m->save = malloc(sizeof(double) * (size_t)nf);
    if (!m->shapes || !m->shape_at || !m->shape_row || !m->shape_y || !m->shape_jac || !m->dq_buf || !m->save) {
        snprintf(why, why_len, "out of memory");
        return ROD_ERR_ALLOC;
    }
    memcpy(m->shapes, shapes, sizeof *m->shapes * (size_t)n);
    m->nshapes = n;
    m->shape_rows = rows;
    rows = 0;
    for (int i = 0; i < n; i++) {
        m->shape_row[i] = rows;
        rows += 2 * shapes[i].k;
        m->shape_at[i] = -1;
        for (int kk = 0; kk < m->nobs && m->shape_at[i] < 0; kk++) {
            const rod_fit_obs *o = &m->obs[m->order[kk]];
            if (o->dl == shapes[i].dl && o->dw == shapes[i].dw) m->shape_at[i] = kk;
        }
        if (m->shape_at[i] < 0) {
            snprintf(why, why_len, "shape %d: no observation at its state (Delta L %.4g, Delta W %.4g)", i + 1,
                     shapes[i].dl, shapes[i].dw);
            m->nshapes = m->shape_rows = 0;
            return ROD_ERR_SCENE;
        }
    }
    return ROD_OK;
}

int rod_fit_model_shape_rows(const rod_fit_model *m, const double **y, const double **jac)
{
    *y = m->shape_y;
    *jac = m->shape_have_jac ? m->shape_jac : NULL;
    return m->shape_rows;
}

/* The shapes modelled at path position kk, whose equilibrium (and, with jac, dq/du) is current. */
static rod_status shapes_at(rod_fit_model *m, int kk, const int *use, int with_jac)
{
    int nf = rod_nfree(m->r);
    for (int i = 0; i < m->nshapes; i++) {
        if (m->shape_at[i] != kk) continue;
        int k = m->shapes[i].k;
        double *y = &m->shape_y[m->shape_row[i]];
        if (rod_shape_sample(m->r, k, y) != 0) return ROD_ERR_NAN;
        if (!with_jac) continue;
        double d[2 * ROD_SHAPE_MAX_POINTS];
        for (int j = 0; j < ROD_FIT_NKEYS; j++) {
            int strip = use[j] && rod_fit_key_strip((rod_fit_key)j);
            if (strip && rod_shape_directional(m->r, k, &m->dq_buf[(size_t)j * (size_t)nf], m->save, d) != 0)
                return ROD_ERR_NAN;
            for (int p = 0; p < 2 * k; p++)
                m->shape_jac[(size_t)(m->shape_row[i] + p) * ROD_FIT_NKEYS + (size_t)j] = strip ? d[p] : 0.0;
        }
    }
    return ROD_OK;
}

rod_status rod_fit_model_eval(rod_fit_model *m, const double u[ROD_FIT_NKEYS], const int *use, double *y,
                              double *jac, char *why, size_t why_len)
{
    rod *r = m->r;
    int solves = 0, followed = 0;
    rod_snapshot *prev = NULL;
    double *dq[ROD_FIT_NKEYS] = {0};
    int none[ROD_FIT_NKEYS] = {0};
    if (!use) use = none;
    m->shape_have_jac = 0;
    rod_fit_apply(r, &m->base, u);
    for (int kk = 0; kk < m->nobs; kk++) {
        int k = m->order[kk];
        const rod_fit_obs *ob = &m->obs[k];
        rod_status st = ROD_ERR_BRANCH_LOST;
        if (kk > 0 && same_state(&m->obs[m->order[kk - 1]], ob)) {
            /* The same clamps as the observation before (a hold's frames): the same equilibrium,
               so the same model values and derivatives, without solving it again. */
            copy_rows(m->order[kk - 1], k, y, jac);
            continue;
        }
        if (m->have[kk] && !followed) {
            rod_snapshot_load(r, &m->state[kk]);
            st = solve_at(m, ob->dl, ob->dw);
        }
        if (st != ROD_OK) {
            /* Once a state's own last equilibrium did not re-solve for these parameters (a long
               step of the fit), neither do the next ones as a rule (measured on the family: each
               a Newton solve run to its cap and failed): they are followed from their
               predecessor, this evaluation's own state, directly. */
            followed = 1;
            if (!prev) {
                /* The route to the scene's own Delta L (the protocol's hold, where its scenes are
                   known to reach the upper state), then along Delta L and Delta W to the first
                   state; the route at the first state's Delta L if that fails. */
                rod_scene sc = m->sc;
                rod_route_report rep = {0};
                st = rod_route_to_state(r, m->s, &sc, +1, &rep);
                if (st == ROD_OK) st = step_to(m, &m->state[kk], sc.compression, 0.0, ob->dl, ob->dw, &solves);
                if (st != ROD_OK && sc.compression != ob->dl) {
                    rod_route_report rep2 = {0};
                    rod_fit_apply(r, &m->base, u);
                    sc.compression = ob->dl;
                    st = rod_route_to_state(r, m->s, &sc, +1, &rep2);
                    if (st == ROD_OK) st = step_to(m, &m->state[kk], ob->dl, 0.0, ob->dl, ob->dw, &solves);
                }
                if (st != ROD_OK) {
                    snprintf(why, why_len, "no upper state at Delta L %.4g, Delta W %.4g for these parameters: %s",
                             ob->dl, ob->dw, rod_status_message(st));
                    return st;
                }
            } else {
                const rod_fit_obs *po = &m->obs[m->order[kk - 1]];
                rod_snapshot_load(r, prev);
                st = step_to(m, &m->state[kk], po->dl, po->dw, ob->dl, ob->dw, &solves);
                if (st != ROD_OK) {
                    snprintf(why, why_len, "the upper state could not be followed from (Delta L %.4g, Delta W %.4g) "
                             "to (%.4g, %.4g) for these parameters: %s", po->dl, po->dw, ob->dl, ob->dw,
                             rod_status_message(st));
                    return st;
                }
            }
        }
        rod_snapshot_save(r, &m->state[kk]);
        m->have[kk] = 1;
        prev = &m->state[kk];
        rod_obs o;
        rod_observe(r, m->k1, &o);
        y[2 * k] = (m->paper ? o.dz : o.dz_cam) + u[ROD_FIT_DZ_OFFSET];
        y[2 * k + 1] = m->paper ? o.a : o.a_cam;
        if (!isfinite(y[2 * k]) || !isfinite(y[2 * k + 1])) {
            snprintf(why, why_len, "non-finite observable at Delta L %.4g, Delta W %.4g", ob->dl, ob->dw);
            return ROD_ERR_NAN;
        }
        int has_shape = 0;
        for (int i = 0; i < m->nshapes; i++) has_shape |= m->shape_at[i] == kk;
        if (has_shape && !jac && shapes_at(m, kk, use, 0) != ROD_OK) {
            snprintf(why, why_len, "the shape at Delta L %.4g, Delta W %.4g is not finite", ob->dl, ob->dw);
            return ROD_ERR_NAN;
        }
        if (jac) {
            rod_obs d[ROD_FIT_NKEYS];
            int neg = 0;
            for (int j = 0; j < ROD_FIT_NKEYS; j++)
                dq[j] = has_shape && use[j] ? &m->dq_buf[(size_t)j * (size_t)rod_nfree(r)] : NULL;
            st = rod_sens_eval(m->sens, r, &m->base, u, use, ob->dl, ob->dw, dq, d, &neg);
            if (st != ROD_OK) {
                snprintf(why, why_len, "the equilibrium at Delta L %.4g, Delta W %.4g is %s", ob->dl, ob->dw,
                         st == ROD_ERR_BRANCH_LOST ? "not stable (its Hessian is not positive definite)"
                                                   : "without finite sensitivities");
                return st;
            }
            for (int j = 0; j < ROD_FIT_NKEYS; j++) {
                jac[(2 * k) * ROD_FIT_NKEYS + j] = use[j] ? (m->paper ? d[j].dz : d[j].dz_cam) : 0.0;
                jac[(2 * k + 1) * ROD_FIT_NKEYS + j] = use[j] ? (m->paper ? d[j].a : d[j].a_cam) : 0.0;
            }
            /* The camera's offset shifts Delta Z by itself and leaves A alone: exact. */
            if (use[ROD_FIT_DZ_OFFSET]) jac[(2 * k) * ROD_FIT_NKEYS + ROD_FIT_DZ_OFFSET] = 1.0;
            if (has_shape && shapes_at(m, kk, use, 1) != ROD_OK) {
                snprintf(why, why_len, "the shape at Delta L %.4g, Delta W %.4g is not finite", ob->dl, ob->dw);
                return ROD_ERR_NAN;
            }
        }
    }
    if (jac) m->shape_have_jac = 1;
    return ROD_OK;
}

/* ---- the fit ---- */

typedef struct fit_ctx {
    rod_fit_model *m;
    const rod_fit_opts *o;
    const rod_fit_obs *obs;
    int nobs, nfit, nres;
    int nshape;                  /* the shapes' data rows, after the 2 nobs of Delta Z and A */
    int key[ROD_FIT_NKEYS];      /* fitted parameter i is key[i] */
    double u0[ROD_FIT_NKEYS], lo[ROD_FIT_NKEYS], hi[ROD_FIT_NKEYS], scale[ROD_FIT_NKEYS];
    double *y, *jac;             /* model at the last evaluation */
    double *last_f;              /* last good residuals */
    double *cache_J;             /* their weighted Jacobian rows */
    int evaluations, failures;
    int cancelled;               /* o->cancel was seen set */
    char why[256];
} fit_ctx;

static void x_to_u(const fit_ctx *c, const double *x, double u[ROD_FIT_NKEYS])
{
    memcpy(u, c->u0, sizeof(double) * ROD_FIT_NKEYS);
    for (int i = 0; i < c->nfit; i++) {
        int k = c->key[i];
        double v = c->u0[k] + c->scale[k] * x[i];
        u[k] = fmin(c->hi[k], fmax(c->lo[k], v));
    }
}

/* The residuals and their Jacobian at x into last_f and cache_J: 0, 1 when the model failed there
   (last_f and cache_J kept, the reason in c->why), -1 when cancelled or past ROD_FIT_LM_FAIL_CAP failures. */
static int eval_point(void *user, const double *x)
{
    fit_ctx *c = user;
    if (c->failures > ROD_FIT_LM_FAIL_CAP) return -1;
    double u[ROD_FIT_NKEYS];
    x_to_u(c, x, u);
    int use[ROD_FIT_NKEYS] = {0};
    for (int i = 0; i < c->nfit; i++) use[c->key[i]] = 1;
    if (c->o->cancel && atomic_load(c->o->cancel)) {
        c->cancelled = 1;
        return -1;
    }
    c->evaluations++;
    char why[256];
    rod_status st = rod_fit_model_eval(c->m, u, use, c->y, c->jac, why, sizeof why);
    if (st != ROD_OK) {
        c->failures++;
        snprintf(c->why, sizeof c->why, "%s", why);
        return 1;
    }
    for (int k = 0; k < c->nobs; k++) {
        const rod_fit_obs *ob = &c->obs[k];
        double w[2] = {1.0 / c->o->sigma_dz, 1.0 / c->o->sigma_a};
        double obsv[2] = {ob->dz, ob->a};
        for (int a = 0; a < 2; a++) {
            int row = 2 * k + a;
            c->last_f[row] = (c->y[row] - obsv[a]) * w[a];
            for (int i = 0; i < c->nfit; i++)
                c->cache_J[row * c->nfit + i] = c->jac[row * ROD_FIT_NKEYS + c->key[i]] * w[a] * c->scale[c->key[i]];
        }
    }
    int row = 2 * c->nobs;
    if (c->nshape) {
        const double *sy, *sj;
        rod_fit_model_shape_rows(c->m, &sy, &sj);
        double w = 1.0 / c->o->sigma_shape;
        for (int i = 0, p = 0; i < c->o->nshapes; i++)
            for (int q = 0; q < 2 * c->o->shapes[i].k; q++, p++, row++) {
                c->last_f[row] = (sy[p] - c->o->shapes[i].xz[q]) * w;
                for (int ii = 0; ii < c->nfit; ii++)
                    c->cache_J[row * c->nfit + ii] =
                        sj ? sj[(size_t)p * ROD_FIT_NKEYS + (size_t)c->key[ii]] * w * c->scale[c->key[ii]] : 0.0;
            }
    }
    for (int i = 0; i < c->nfit; i++) {
        int k = c->key[i];
        if (!isfinite(c->o->prior_sigma[k])) continue;
        double centre = c->o->prior_centre && isfinite(c->o->prior_centre[k]) ? c->o->prior_centre[k] : c->u0[k];
        c->last_f[row] = (u[k] - centre) / c->o->prior_sigma[k];
        for (int ii = 0; ii < c->nfit; ii++)
            c->cache_J[row * c->nfit + ii] = ii == i ? c->scale[k] / c->o->prior_sigma[k] : 0.0;
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

/* Covariance, standard errors, correlations and the undetermined directions from the weighted
   Jacobian Jw (nres x nfit, data rows first) at the solution (rod_fit_lm.h), by key. */
static int covariance(fit_ctx *c, const double *Jw, rod_fit_result *res)
{
    int p = c->nfit;
    double lo[ROD_FIT_NKEYS], hi[ROD_FIT_NKEYS], scale[ROD_FIT_NKEYS], prior[ROD_FIT_NKEYS];
    double cov[ROD_FIT_NKEYS * ROD_FIT_NKEYS], corr[ROD_FIT_NKEYS * ROD_FIT_NKEYS], se[ROD_FIT_NKEYS];
    int det[ROD_FIT_NKEYS];
    for (int j = 0; j < p; j++) {
        int k = c->key[j];
        lo[j] = c->lo[k];
        hi[j] = c->hi[k];
        scale[j] = c->scale[k];
        prior[j] = c->o->prior_sigma[k];
    }
    int *phase = malloc((size_t)c->nobs * sizeof *phase);
    if (!phase) return -1;
    rod_fit_phases(c->obs, c->nobs, phase);
    double factor = 1.0;
    if (c->o->scale_covariance && c->nres > p) factor = res->chi2 / (double)(c->nres - p);
    res->cov_scaled = factor != 1.0;
    rod_fit_lm_cov_in in = {.p = p, .nres = c->nres, .nobs = c->nobs, .nshape = c->nshape, .Jw = Jw, .f = c->last_f, .lo = lo, .hi = hi,
                            .scale = scale, .prior = prior, .factor = factor, .phase = phase,
                            .sigma = {c->o->sigma_dz, c->o->sigma_a}, .sigma_b = {c->o->sigma_b_dz, c->o->sigma_b_a}};
    int *rows = NULL;
    if (c->nshape && c->o->shape_common_mode) {
        rows = malloc((size_t)c->o->nshapes * sizeof *rows);
        if (!rows) {
            free(phase);
            return -1;
        }
        for (int i = 0; i < c->o->nshapes; i++) rows[i] = 2 * (c->o->shapes[i].k > 0 ? c->o->shapes[i].k : 0);
        in.nshapes = c->o->nshapes;
        in.shape_rows = rows;
    }
    rod_fit_lm_cov_out out = {.cov = cov, .corr = corr, .se = se, .determined = det};
    int rc = rod_fit_lm_covariance(&in, &out);
    free(phase);
    free(rows);
    if (rc) return -1;
    res->sv_min = out.sv_min;
    res->sv_max = out.sv_max;
    res->sigma_b[0] = out.sigma_b[0];
    res->sigma_b[1] = out.sigma_b[1];
    for (int a = 0; a < p; a++) {
        int ka = c->key[a];
        res->se[ka] = se[a];
        res->determined[ka] = det[a];
        for (int b = 0; b < p; b++) {
            res->cov[ka][c->key[b]] = cov[a * p + b];
            res->corr[ka][c->key[b]] = corr[a * p + b];
        }
    }
    return 0;
}

rod_status rod_fit_run(const rod_scene *sc, const rod_fit_obs *obs, int nobs, const rod_fit_opts *o,
                       rod_fit_result *res, char *why, size_t why_len)
{
    double t0 = now_s();
    memset(res, 0, sizeof *res);
    fit_ctx c;
    memset(&c, 0, sizeof c);
    c.o = o;
    c.obs = obs;
    c.nobs = nobs;
    rod_fit_scene_values(sc, c.u0);
    memcpy(res->u0, c.u0, sizeof c.u0);
    memcpy(res->u, c.u0, sizeof c.u0);
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        res->se[k] = 0.0;
        if (!o->fit[k]) continue;
        if (rod_fit_key_usable(sc, (rod_fit_key)k, why, why_len)) return ROD_ERR_SCENE;
        double lo, hi;
        rod_fit_key_bounds((rod_fit_key)k, c.u0[k], &lo, &hi);
        if (!isnan(o->lo[k])) lo = o->lo[k];
        if (!isnan(o->hi[k])) hi = o->hi[k];
        if (!(lo < hi) || !(lo <= c.u0[k] && c.u0[k] <= hi)) {
            snprintf(why, why_len, "%s: the bounds [%g, %g] do not hold the scene's value %g", rod_fit_key_name(k),
                     lo, hi, c.u0[k]);
            return ROD_ERR_SCENE;
        }
        if (!(o->prior_sigma[k] > 0.0)) {
            snprintf(why, why_len, "%s: the prior's width must be positive", rod_fit_key_name(k));
            return ROD_ERR_SCENE;
        }
        c.lo[k] = lo;
        c.hi[k] = hi;
        c.scale[k] = rod_fit_key_scale((rod_fit_key)k);
        res->fitted[k] = 1;
        c.key[c.nfit++] = k;
    }
    if (o->fit[ROD_FIT_HINGE] && (o->fit[ROD_FIT_HINGE_LEFT] || o->fit[ROD_FIT_HINGE_RIGHT])) {
        snprintf(why, why_len, "%s with %s: one hinge stiffness for both creases or one each, not both",
                 rod_fit_key_name(ROD_FIT_HINGE),
                 rod_fit_key_name(o->fit[ROD_FIT_HINGE_LEFT] ? ROD_FIT_HINGE_LEFT : ROD_FIT_HINGE_RIGHT));
        return ROD_ERR_SCENE;
    }
    memcpy(res->lo, c.lo, sizeof c.lo);
    memcpy(res->hi, c.hi, sizeof c.hi);
    if (c.nfit == 0) {
        snprintf(why, why_len, "no parameter to fit (--fit names them: folds.angle_left_deg, ...)");
        return ROD_ERR_SCENE;
    }
    if (!(o->sigma_dz > 0.0) || !(o->sigma_a > 0.0) || !isfinite(o->sigma_dz) || !isfinite(o->sigma_a)) {
        snprintf(why, why_len, "the noise of Delta Z and of A must be positive and finite");
        return ROD_ERR_SCENE;
    }
    if (!isfinite(o->sigma_b_dz) || !isfinite(o->sigma_b_a)) {
        snprintf(why, why_len, "the tracker's common-mode error (sigma_b) of Delta Z and of A must be finite");
        return ROD_ERR_SCENE;
    }
    int need = c.nfit + 1 > o->min_obs ? c.nfit + 1 : o->min_obs;
    if (nobs < need) {
        snprintf(why, why_len, "too few observations: %d for %d fitted parameter%s (at least %d needed)", nobs,
                 c.nfit, c.nfit == 1 ? "" : "s", need);
        return ROD_ERR_SCENE;
    }
    for (int k = 0; k < nobs; k++)
        if (!isfinite(obs[k].dl) || !isfinite(obs[k].dw) || !isfinite(obs[k].dz) || !isfinite(obs[k].a) ||
            obs[k].dl <= 0.0 || obs[k].dl >= 1.0) {
            snprintf(why, why_len, "observation %d: Delta L must be in (0, 1) and every value finite", k + 1);
            return ROD_ERR_SCENE;
        }
    if (o->nshapes < 0 || (o->nshapes > 0 && (!o->shapes || !(o->sigma_shape > 0.0) || !isfinite(o->sigma_shape)))) {
        snprintf(why, why_len, "shapes: the noise of a shape's points must be positive and finite");
        return ROD_ERR_SCENE;
    }
    int npri = 0;
    for (int i = 0; i < c.nfit; i++) npri += isfinite(o->prior_sigma[c.key[i]]);
    for (int i = 0; i < o->nshapes; i++) c.nshape += 2 * (o->shapes[i].k > 0 ? o->shapes[i].k : 0);
    int ndata = 2 * nobs + c.nshape;
    c.nres = ndata + npri;
    res->nobs = nobs;
    res->nres = ndata;
    res->nshape_rows = c.nshape;
    res->nfit = c.nfit;
    rod_status st = rod_fit_model_alloc(sc, obs, nobs, o->paper, &c.m, why, why_len);
    if (st != ROD_OK) return st;
    st = rod_fit_model_set_shapes(c.m, o->shapes, o->nshapes, why, why_len);
    if (st != ROD_OK) {
        rod_fit_model_free(c.m);
        return st;
    }
    c.y = malloc(sizeof(double) * 2 * (size_t)nobs);
    c.jac = malloc(sizeof(double) * 2 * (size_t)nobs * ROD_FIT_NKEYS);
    c.last_f = calloc((size_t)c.nres, sizeof(double));
    c.cache_J = calloc((size_t)c.nres * (size_t)c.nfit, sizeof(double));
    double x[ROD_FIT_NKEYS] = {0}; /* the scene's values */
    if (!c.y || !c.jac || !c.last_f || !c.cache_J) {
        snprintf(why, why_len, "out of memory");
        st = ROD_ERR_ALLOC;
        goto done;
    }
    /* At the scene's values first: a model that fails there is the caller's to know. */
    if (eval_point(&c, x)) {
        if (c.cancelled) goto cancelled;
        snprintf(why, why_len, "the scene's own strip: %s", c.why);
        st = ROD_ERR_BRANCH_LOST;
        goto done;
    }
    {
        double s = 0.0;
        for (int i = 0; i < ndata; i++) s += c.last_f[i] * c.last_f[i];
        res->rms_start = sqrt(s / (double)ndata);
    }
    if (o->start) /* the caller's start (opts.start): a fit without the shapes, say */
        for (int i = 0; i < c.nfit; i++) {
            int k = c.key[i];
            double v = o->start[k];
            if (isfinite(v)) x[i] = (fmin(fmax(v, c.lo[k]), c.hi[k]) - c.u0[k]) / c.scale[k];
        }
    rod_fit_lm_problem pr = {.p = c.nfit, .nres = c.nres, .eval = eval_point, .last_f = c.last_f, .last_J = c.cache_J,
                             .user = &c};
    st = rod_fit_lm_drive(&pr, x, o->max_iterations, o->stop_sd, &res->iterations, &res->gn_sd, &res->capped, why,
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
        snprintf(why, why_len, "the fitted strip: %s", c.why);
        st = ROD_ERR_BRANCH_LOST;
        goto done;
    }
    x_to_u(&c, x, res->u);
    for (int i = 0; i < ndata; i++) res->chi2 += c.last_f[i] * c.last_f[i];
    res->rms = sqrt(res->chi2 / (double)ndata);
    if (c.nshape) {
        double s = 0.0;
        for (int i = 2 * nobs; i < ndata; i++) s += c.last_f[i] * c.last_f[i];
        res->shape_rms = sqrt(s / (double)c.nshape);
    }
    res->misfit = res->rms > o->misfit;
    for (int i = 0; i < c.nfit; i++) {
        int k = c.key[i];
        double tol = 1e-9 * (c.hi[k] - c.lo[k]);
        res->at_bound[k] = res->u[k] <= c.lo[k] + tol ? -1 : res->u[k] >= c.hi[k] - tol ? 1 : 0;
    }
    if (covariance(&c, c.cache_J, res)) {
        snprintf(why, why_len, "out of memory");
        st = ROD_ERR_ALLOC;
        goto done;
    }
    res->model_failures = c.failures;
    st = ROD_OK;
    goto done;
cancelled:
    snprintf(why, why_len, "cancelled");
    st = ROD_ERR_TIME_LIMIT;
done:
    res->evaluations = c.evaluations;
    res->wall_s = now_s() - t0;
    free(c.y);
    free(c.jac);
    free(c.last_f);
    free(c.cache_J);
    rod_fit_model_free(c.m);
    return st;
}
