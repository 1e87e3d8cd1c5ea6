/* rod_sensitivity.c: the equilibrium's and the observables' derivatives in the strip parameters
 * (rod_sensitivity.h). */
#include "rod_sensitivity.h"

#include "rod_band.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct rod_sens_ws {
    int nfree, ndof;
    double *H, *g, *gp, *rhs, *k1;
    rod_snapshot at;
};

rod_sens_ws *rod_sens_alloc(const rod *r)
{
    rod_sens_ws *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    w->nfree = rod_nfree(r);
    w->ndof = r->ndof;
    w->H = malloc(sizeof(double) * (size_t)w->nfree * (ROD_BAND + 1));
    w->g = malloc(sizeof(double) * (size_t)w->ndof);
    w->gp = malloc(sizeof(double) * (size_t)w->ndof);
    w->rhs = malloc(sizeof(double) * (size_t)w->nfree);
    w->k1 = malloc(sizeof(double) * (size_t)r->n);
    if (!w->H || !w->g || !w->gp || !w->rhs || !w->k1 || !rod_snapshot_alloc(r, &w->at)) {
        rod_sens_free(w);
        return NULL;
    }
    return w;
}

void rod_sens_free(rod_sens_ws *w)
{
    if (!w) return;
    free(w->H);
    free(w->g);
    free(w->gp);
    free(w->rhs);
    free(w->k1);
    rod_snapshot_free(&w->at);
    free(w);
}

double rod_sens_step(rod_fit_key k)
{
    switch (k) {
    case ROD_FIT_ANGLE_LEFT:
    case ROD_FIT_ANGLE_RIGHT: return 1e-3;      /* deg */
    case ROD_FIT_POSITION_LEFT:
    case ROD_FIT_POSITION_RIGHT: return 1e-6;   /* of l */
    default: return 1e-4;                       /* ln units */
    }
}

/* The rod at parameters u + t e_j with the free DOFs q_eq + t dir (dir NULL: q_eq), clamps
   placed, frames transported from the equilibrium's. */
static void perturbed(rod_sens_ws *w, rod *r, const rod_fit_base *b, const double u[ROD_FIT_NKEYS], int j,
                      double t, const double *dir, double dl, double dw)
{
    double up[ROD_FIT_NKEYS];
    memcpy(up, u, sizeof up);
    up[j] += t;
    rod_snapshot_load(r, &w->at);
    rod_fit_apply(r, b, up);
    rod_set_clamps(r, dl, dw);
    if (dir)
        for (int i = 0; i < w->nfree; i++) r->q[ROD_FREE_BEGIN + i] += t * dir[i];
    rod_frames_update(r);
}

rod_status rod_sens_eval(rod_sens_ws *w, rod *r, const rod_fit_base *b, const double u[ROD_FIT_NKEYS],
                         const int use[ROD_FIT_NKEYS], double dl, double dw, double *dq[ROD_FIT_NKEYS],
                         rod_obs dobs[ROD_FIT_NKEYS], int *n_negative)
{
    int nf = w->nfree;
    rod_snapshot_save(r, &w->at);
    memset(w->H, 0, sizeof(double) * (size_t)nf * (ROD_BAND + 1));
    rod_gradient_hessian(r, NULL, 1.0, w->H);
    if (n_negative) *n_negative = 0;
    if (rod_band_ldlt_decomp(w->H, nf) != 0) {
        if (n_negative) *n_negative = 1;
        return ROD_ERR_BRANCH_LOST;
    }
    int neg = 0;
    for (int i = 0; i < nf; i++)
        if (!(w->H[i * (ROD_BAND + 1)] > 0.0)) neg++;
    if (neg) {
        if (n_negative) *n_negative = neg;
        return ROD_ERR_BRANCH_LOST;
    }
    rod_status st = ROD_OK;
    for (int j = 0; j < ROD_FIT_NKEYS && st == ROD_OK; j++) {
        if (!use[j]) continue;
        if (!rod_fit_key_strip((rod_fit_key)j)) { /* the equilibrium does not depend on it */
            if (dq[j]) memset(dq[j], 0, sizeof(double) * (size_t)nf);
            memset(&dobs[j], 0, sizeof dobs[j]);
            continue;
        }
        double h = rod_sens_step((rod_fit_key)j);
        perturbed(w, r, b, u, j, h, NULL, dl, dw);
        rod_gradient(r, w->gp);
        perturbed(w, r, b, u, j, -h, NULL, dl, dw);
        rod_gradient(r, w->g);
        for (int i = 0; i < nf; i++)
            w->rhs[i] = -(w->gp[ROD_FREE_BEGIN + i] - w->g[ROD_FREE_BEGIN + i]) / (2.0 * h);
        rod_band_ldlt_solve(w->H, nf, w->rhs);
        for (int i = 0; i < nf; i++)
            if (!isfinite(w->rhs[i])) st = ROD_ERR_NAN;
        if (st != ROD_OK) break;
        if (dq[j]) memcpy(dq[j], w->rhs, sizeof(double) * (size_t)nf);
        rod_obs op, om;
        perturbed(w, r, b, u, j, h, w->rhs, dl, dw);
        rod_observe(r, w->k1, &op);
        perturbed(w, r, b, u, j, -h, w->rhs, dl, dw);
        rod_observe(r, w->k1, &om);
        dobs[j].dz = (op.dz - om.dz) / (2.0 * h);
        dobs[j].a = (op.a - om.a) / (2.0 * h);
        dobs[j].a_cam = (op.a_cam - om.a_cam) / (2.0 * h);
        dobs[j].dz_cam = (op.dz_cam - om.dz_cam) / (2.0 * h);
        if (!isfinite(dobs[j].dz) || !isfinite(dobs[j].a) || !isfinite(dobs[j].a_cam) || !isfinite(dobs[j].dz_cam))
            st = ROD_ERR_NAN;
    }
    rod_snapshot_load(r, &w->at);
    rod_fit_apply(r, b, u);
    rod_set_clamps(r, dl, dw);
    rod_frames_update(r);
    return st;
}
