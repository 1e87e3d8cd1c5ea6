/* rod_route.c: quasi-static stepping (see rod_route.h). */
#include "rod_route.h"
#include "rod_observe.h"
#include "rod_stability.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Arc length over [0, 1] of u -> (D u, H (1 - cos 2 pi u) / 2), by the midpoint rule. */
static double arch_length(double D, double H, int m)
{
    double L = 0.0;
    for (int k = 0; k < m; k++) {
        double u = (k + 0.5) / m;
        L += hypot(D, H * M_PI * sin(2.0 * M_PI * u)) / m;
    }
    return L;
}

void rod_place_arch(rod *r, double dl, int branch)
{
    double l = r->length, D = l * (1.0 - dl);
    rod_set_clamps(r, dl, 0.0);
    double lo = 0.0, hi = l;
    for (int it = 0; it < 100; it++) {
        double mid = 0.5 * (lo + hi);
        if (arch_length(D, mid, 400) < l) lo = mid; else hi = mid;
    }
    double H = 0.5 * (lo + hi) * (branch >= 0 ? 1.0 : -1.0);
    /* Walk the arch with a fine table of arc length and place nodes at their rest arc length. */
    int m = 4000;
    double u_prev = 0.0, s_prev = 0.0;
    int node = 2;
    double scale = l / arch_length(D, H, m);
    for (int k = 1; k <= m && node < r->n - 2; k++) {
        double u = (double)k / m, um = (k - 0.5) / m;
        double s = s_prev + scale * hypot(D, H * M_PI * sin(2.0 * M_PI * um)) / m;
        while (node < r->n - 2 && r->s_node[node] * l <= s) {
            double uu = u_prev + (u - u_prev) * (r->s_node[node] * l - s_prev) / (s - s_prev);
            double *x = rod_x(r, node);
            x[0] = D * uu;
            x[1] = 0.0;
            x[2] = 0.5 * H * (1.0 - cos(2.0 * M_PI * uu));
            node++;
        }
        u_prev = u;
        s_prev = s;
    }
    for (int i = 1; i < r->n - 2; i++) r->q[4 * i + 3] = 0.0;
    rod_frames_update(r);
}

/* Moves the right clamp to (dl, dw) and carries the free nodes along affinely, a predictor that
 * keeps edge strains small. */
static void move_clamps(rod *r, double dl_old, double dw_old, double dl, double dw)
{
    double l = r->length, sx = (1.0 - dl) / (1.0 - dl_old);
    for (int i = 2; i < r->n - 2; i++) {
        double *x = rod_x(r, i);
        x[0] *= sx;
        x[1] += (dw - dw_old) * l * (r->s_node[i] - 0.5);
    }
    rod_set_clamps(r, dl, dw);
}

typedef struct stage {
    double dl0, dl1;    /* compression from, to */
    double f0, f1;      /* crease fraction from, to */
} stage;

/* One stage: parameter p from 0 to 1, dl and the crease fraction linear in p.
 *
 * Predictor: after two converged states the free DOFs are extrapolated along the secant through
 * them (the path is smooth in p), which starts Newton within a few iterations of the new state;
 * before that, the affine move of the nodes with the clamp (the plain predictor). The affine move
 * alone is a poor start for long compressions: it shortens every edge, the compressed edges make
 * the Hessian indefinite, and Newton needed 12-50 shifted iterations per step. A secant start that
 * ends in a non-finite value (ROD_ERR_NAN: a trial state with a degenerate edge or frame) is a
 * failed trial, not the end of the route: the same step is retried once from the plain predictor
 * on the last converged state, then halved as any other failure.
 * Step: from 1 / nsteps, halved on failure, grown by half while Newton converges in at most 5
 * iterations, never beyond 2 / nsteps nor below 2^-ROUTE_MIN_STEP_LOG2 / nsteps. Every accepted
 * step therefore advances p by at least that minimum, so the secant's p - p_prev never vanishes.
 * (Without the minimum, steps that failed at 50 iterations and succeeded at 0 iterations (a
 * state already within the loose tolerance) shrank the step geometrically to below one ulp of
 * p: p + dp == p was accepted, p_prev = p, and the next secant coefficient (pn - p) / (p - p_prev)
 * was 0 / 0, which wrote NaN into every free DOF.)
 * Stop: a failure that would cut the step below the minimum ends the stage. Its status is
 * ROD_ERR_BRANCH_LOST when the last converged state has a (verified) negative eigenvalue of the
 * Hessian: the stable state being followed has ceased to exist; otherwise the status of the
 * last failed solve (iteration cap, line search, ...). At most ROUTE_SOLVES_PER_STEP * nsteps
 * solves per stage (ROD_ERR_ROUTE_CAP). The residual reported on failure is the last failed
 * solve's when finite, else the last converged state's.
 * Tolerance: intermediate states only seed the next step, so they are solved to a looser
 * residual (ROUTE_LOOSE, relative to E I1 / l^2, or the scene's if looser); the stage's last
 * state is solved to the scene's tolerance. */
#define ROUTE_LOOSE 1e-3
#define ROUTE_MIN_STEP_LOG2 10   /* smallest step 2^-10 / nsteps: the former cap of 10 halvings */
#define ROUTE_SOLVES_PER_STEP 40 /* cap on static solves per stage, per nominal step */

/* Why the stage stopped at its smallest step (see run_stage): a verified negative eigenvalue of
 * the Hessian at the last converged state says the followed branch has lost its stability. */
static rod_status stop_reason(rod *r, rod_status last_failure)
{
    int nf = rod_nfree(r);
    double *H = calloc((size_t)nf * (ROD_BAND + 1), sizeof(double));
    rod_stab_ws *w = rod_stab_ws_alloc(nf);
    rod_status st = last_failure;
    if (H && w) {
        rod_inertia in;
        char why[160];
        rod_hessian_add(r, 1.0, H);
        if (rod_inertia_eval(H, nf, ROD_INERTIA_SHIFT_REL, w, &in, why, sizeof why) == ROD_OK && in.verified &&
            in.n_negative > 0)
            st = ROD_ERR_BRANCH_LOST;
    }
    free(H);
    rod_stab_ws_free(w);
    return st;
}

/* Residual of the current state over the force scale, without moving it (a solve capped at zero
 * iterations only evaluates the residual). */
static double state_residual(rod *r, rod_solver *s, rod_newton_opts o)
{
    rod_newton_report nr;
    o.max_iterations = 0;
    rod_newton_solve(r, s, &o, &nr);
    return nr.residual_rel;
}

static rod_status run_stage(rod *r, rod_solver *s, const rod_scene *sc, const stage *g, int nsteps,
                            rod_route_report *rep)
{
    rod_newton_opts o = rod_newton_opts_static(sc);
    o.positive_definite = 1; /* the route and the followed branch are stable states */
    double tol_final = o.tolerance, tol_loose = fmax(o.tolerance, ROUTE_LOOSE);
    size_t nd = (size_t)r->ndof;
    double *q0 = malloc(sizeof(double) * nd), *q1 = malloc(sizeof(double) * nd);
    if (!q0 || !q1) {
        free(q0);
        free(q1);
        return ROD_ERR_ALLOC;
    }
    double p = 0.0, p_prev = 0.0, dp = 1.0 / nsteps, dp_max = 2.0 / nsteps;
    double dp_min = ldexp(1.0 / nsteps, -ROUTE_MIN_STEP_LOG2);
    int have_prev = 0, plain = 0, solves = 0, max_solves = ROUTE_SOLVES_PER_STEP * nsteps;
    rod_status st = ROD_OK;
    double fail_res = NAN;
    rod_state_save(r, s, 0);
    memcpy(q0, r->q, sizeof(double) * nd);
    while (p < 1.0) {
        if (solves >= max_solves) {
            st = ROD_ERR_ROUTE_CAP;
            break;
        }
        double pn = fmin(1.0, p + dp);
        if (1.0 - pn < 0.25 * dp) pn = 1.0; /* no sliver of a last step */
        double dl_old = g->dl0 + p * (g->dl1 - g->dl0), dl = g->dl0 + pn * (g->dl1 - g->dl0);
        int secant = have_prev && !plain;
        if (secant) {
            /* p - p_prev >= dp_min > 0: every accepted step advanced p by at least dp_min. */
            double c = (pn - p) / (p - p_prev);
            for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) r->q[k] = q0[k] + c * (q0[k] - q1[k]);
            rod_set_clamps(r, dl, 0.0);
        } else {
            move_clamps(r, dl_old, 0.0, dl, 0.0);
        }
        if (rep->inject_nan_solve > 0 && rep->solves + 1 == rep->inject_nan_solve)
            r->q[r->free_end - 1] = NAN; /* fault injection (rod_route.h) */
        double f = g->f0 + pn * (g->f1 - g->f0);
        rod_set_folds(r, f, f);
        o.tolerance = pn >= 1.0 ? tol_final : tol_loose;
        rod_newton_report nr;
        st = rod_newton_solve(r, s, &o, &nr);
        solves++;
        rep->solves++;
        rep->newton_iterations += nr.iterations;
        rep->residual_rel = nr.residual_rel;
        if (st == ROD_OK) {
            p_prev = p;
            p = pn;
            memcpy(q1, q0, sizeof(double) * nd);
            memcpy(q0, r->q, sizeof(double) * nd);
            have_prev = 1;
            plain = 0;
            rod_state_save(r, s, 0);
            if (nr.iterations <= 5) dp = fmin(1.5 * dp, dp_max);
            continue;
        }
        rep->last_failure = st;
        if (isfinite(nr.residual_rel)) fail_res = nr.residual_rel;
        rod_state_restore(r, s, 0);
        rod_set_folds(r, g->f0 + p * (g->f1 - g->f0), g->f0 + p * (g->f1 - g->f0));
        if (secant && st == ROD_ERR_NAN) {
            plain = 1; /* the same step once more, from the plain predictor */
            continue;
        }
        plain = 0;
        if (0.5 * dp < dp_min) {
            st = stop_reason(r, rep->last_failure);
            break;
        }
        dp *= 0.5;
    }
    free(q0);
    free(q1);
    if (st != ROD_OK) {
        rep->reached = p;
        rep->residual_rel = isfinite(fail_res) ? fail_res : state_residual(r, s, o);
        return st;
    }
    rep->reached = 1.0;
    return ROD_OK;
}

rod_status rod_route_to_state(rod *r, rod_solver *s, const rod_scene *sc, int branch,
                              rod_route_report *rep)
{
    rod_route_report local = {0};
    if (!rep) rep = &local;
    double dl = sc->compression, dl0 = fmin(dl, 0.05);
    rod_set_folds(r, 0.0, 0.0);
    rod_place_arch(r, dl0, branch);
    stage first = {dl0, dl0, 0.0, 0.0};
    rod_status st = run_stage(r, s, sc, &first, 1, rep);
    if (st != ROD_OK) return st;
    if (sc->route == ROD_ROUTE_TOGETHER) {
        stage both = {dl0, dl, 0.0, 1.0};
        return run_stage(r, s, sc, &both, 40, rep);
    }
    stage compress = {dl0, dl, 0.0, 0.0};
    st = run_stage(r, s, sc, &compress, 20, rep);
    if (st != ROD_OK) return st;
    stage fold = {dl, dl, 0.0, 1.0};
    return run_stage(r, s, sc, &fold, 20, rep);
}

rod_status rod_follow_shear(rod *r, rod_solver *s, const rod_scene *sc, double dl, double dw_from,
                            double dw_to, double dw_step, double *dw_reached, rod_route_report *rep)
{
    rod_route_report local = {0};
    if (!rep) rep = &local;
    rod_newton_opts o = rod_newton_opts_static(sc);
    o.positive_definite = 1; /* the route and the followed branch are stable states */
    double *k1 = malloc(sizeof(double) * (size_t)r->n);
    if (!k1) return ROD_ERR_ALLOC;
    rod_obs ob;
    rod_observe(r, k1, &ob);
    double dw = dw_from, dz_prev = ob.dz;
    double step = dw_step * (dw_to >= dw_from ? 1.0 : -1.0);
    int halvings = 0;
    rod_status st = ROD_OK;
    rod_state_save(r, s, 0);
    int cap = 100000;
    while (fabs(dw_to - dw) > 1e-15 && cap-- > 0) {
        double dn = dw + step;
        if ((step > 0 && dn > dw_to) || (step < 0 && dn < dw_to)) dn = dw_to;
        move_clamps(r, dl, dw, dl, dn);
        rod_newton_report nr;
        st = rod_newton_solve(r, s, &o, &nr);
        rep->solves++;
        rep->newton_iterations += nr.iterations;
        rep->residual_rel = nr.residual_rel;
        if (st == ROD_OK) {
            rod_observe(r, k1, &ob);
            /* A jump in Delta Z much larger than the step means Newton left the branch. */
            if (fabs(ob.dz - dz_prev) > 0.02 + 20.0 * fabs(dn - dw)) st = ROD_ERR_BRANCH_LOST;
        }
        if (st == ROD_OK) {
            dw = dn;
            dz_prev = ob.dz;
            rod_state_save(r, s, 0);
            if (halvings > 0 && nr.iterations < 5) { step *= 2.0; halvings--; }
            continue;
        }
        rod_state_restore(r, s, 0);
        if (++halvings > 12) {
            st = ROD_ERR_BRANCH_LOST;
            break;
        }
        step *= 0.5;
        st = ROD_OK;
    }
    if (cap <= 0 && st == ROD_OK) st = ROD_ERR_MAXITER;
    if (dw_reached) *dw_reached = dw;
    free(k1);
    return st;
}
