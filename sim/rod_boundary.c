/* rod_boundary.c: the codimension-2 search from a scene, its continuation in phi and Delta L,
 * and the fold and pitchfork curves through it (rod_boundary.h).
 *
 * A point of any of these curves is a rod state with its parameters and mesh (bpoint); the
 * session keeps the current codimension-2 point and, inside one continuation, the two before it
 * for the quadratic predictor (the secant when only one is known). Re-meshing (match_mesh) moves
 * a state to another outer edge count by linear interpolation in arc length of the node positions and of the twist angles (at edge
 * midpoints); the augmented Newton then re-converges from there. */
#include "rod_boundary.h"
#include "rod_bifurcation.h"
#include "rod_observe.h"
#include "rod_route.h"
#include "rod_snapshot.h"
#include "rod_solver.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct bpoint {
    rod_snapshot snap;
    double p[ROD_NPAR];
    int n_out;
    rod_codim2_point info;
} bpoint;

struct rod_boundary {
    rod_scene sc;          /* the perfect scene of the start */
    rod_boundary_opts o;
    rod *r;
    rod_crit *c;
    rod_solver *solver;    /* static solves after a re-mesh */
    double sign;           /* sign of the crease angle */
    double *k1;
    bpoint cur, prev, prev2, trial;
    bpoint scur, sprev;    /* the search's own last two points */
    bpoint mark;           /* rod_boundary_mark */
    int prev_valid;        /* prev is the point before cur on a continuation in prev_par */
    int prev2_valid;       /* and prev2 the point before prev, on the same continuation */
    rod_par prev_par;
    int check_valid;       /* last_check is where a move in check_par last verified the point */
    rod_par check_par;
    double last_check;
    double slope;          /* d g_odd / d Gamma along the fold curve at the last codim-2 point */
    char why[200];         /* the last augmented solve's failure */
    char msg[400];         /* the last search's failure */
};

rod_boundary_opts rod_boundary_opts_default(void)
{
    rod_boundary_opts o;
    memset(&o, 0, sizeof o);
    o.crit = rod_crit_opts_default();
    o.cont = rod_cont_opts_default();
    o.gamma_min = 0.02;
    o.gamma_max = 0.45;
    o.gamma_step = 0.02;
    o.max_search = 40;
    o.phi_step_deg = 5.0;
    o.dl_step = 0.05;
    o.min_step_frac = 1.0 / 64.0;
    o.max_steps = 400;
    o.match_mesh = 0;
    o.verify_every = 10.0;
    o.direct = 0;
    o.verify_ends = 1;
    o.phase1_cap = 20;
    o.predictor = 2;
    return o;
}

void rod_boundary_curve_free(rod_boundary_curve *c)
{
    free(c->pts);
    c->pts = NULL;
    c->n = c->cap = 0;
}

void rod_crit_curve_free(rod_crit_curve *c)
{
    free(c->pts);
    c->pts = NULL;
    c->n = c->cap = 0;
}

static int bpoint_alloc(const rod *r, bpoint *b)
{
    memset(b, 0, sizeof *b);
    return rod_snapshot_alloc(r, &b->snap);
}

static void bpoint_copy(const bpoint *from, bpoint *to)
{
    rod_snapshot_copy(&from->snap, &to->snap);
    memcpy(to->p, from->p, sizeof to->p);
    to->n_out = from->n_out;
    to->info = from->info;
}

void rod_boundary_free(rod_boundary *b)
{
    if (!b) return;
    rod_snapshot_free(&b->cur.snap);
    rod_snapshot_free(&b->prev.snap);
    rod_snapshot_free(&b->prev2.snap);
    rod_snapshot_free(&b->trial.snap);
    rod_snapshot_free(&b->scur.snap);
    rod_snapshot_free(&b->mark.snap);
    rod_snapshot_free(&b->sprev.snap);
    rod_crit_free(b->c);
    rod_solver_free(b->solver);
    rod_free(b->r);
    free(b->k1);
    free(b);
}

rod_counters rod_boundary_counters(const rod_boundary *b) { return b->r->count; }

void rod_boundary_current(const rod_boundary *b, rod_codim2_point *out) { *out = b->cur.info; }

/* The rod takes point bp's mesh, parameters and state. */
static void load_point(rod_boundary *b, const bpoint *bp)
{
    b->r->fold_outer_edges = bp->n_out;
    rod_params_apply(b->r, bp->p);
    rod_snapshot_load(b->r, &bp->snap);
    rod_params_apply(b->r, bp->p);
}

void rod_boundary_mark(rod_boundary *b) { bpoint_copy(&b->cur, &b->mark); }

void rod_boundary_return(rod_boundary *b)
{
    b->prev_valid = 0;
    b->prev2_valid = 0;
    b->check_valid = 0;
    bpoint_copy(&b->mark, &b->cur);
    load_point(b, &b->cur);
    rod_crit_update_borders(b->c, b->cur.p);
    load_point(b, &b->cur);
}

static void save_point(rod_boundary *b, const double *p, bpoint *bp)
{
    rod_snapshot_save(b->r, &bp->snap);
    memcpy(bp->p, p, sizeof bp->p);
    bp->n_out = b->r->fold_outer_edges;
}

/* Moves the state to the mesh with n_out outer edges (rod_crit_move_gamma interpolates, which
 * strains the curved edges at second order), then restores equilibrium a little below the fold
 * in Delta W, where the upper branch is stable, by the static solver (minimisation): the
 * augmented Newton then starts from an equilibrium. p[DW] is lowered accordingly. */
static void remesh(rod_boundary *b, double *p, int n_out)
{
    int changed = n_out != b->r->fold_outer_edges;
    rod_crit_move_gamma(b->c, p, n_out);
    if (!b->solver || !changed) return;
    double p2[ROD_NPAR];
    memcpy(p2, p, sizeof p2);
    p2[ROD_PAR_DW] = p[ROD_PAR_DW] - 0.01;
    rod_params_apply(b->r, p2);
    rod_newton_opts no = rod_newton_opts_static(&b->sc);
    no.positive_definite = 1;
    no.max_iterations = 200;
    rod_newton_report nr;
    rod_state_save(b->r, b->solver, 0);
    if (rod_newton_solve(b->r, b->solver, &no, &nr) == ROD_OK) {
        p[ROD_PAR_DW] = p2[ROD_PAR_DW];
    } else {
        rod_state_restore(b->r, b->solver, 0);
        rod_params_apply(b->r, p);
    }
}

static void fill_info(rod_boundary *b, const double *p, const rod_crit_report *rep, rod_codim2_point *pt)
{
    rod_obs ob;
    rod_observe(b->r, b->k1, &ob);
    memset(pt, 0, sizeof *pt);
    pt->phi_deg = fabs(p[ROD_PAR_PHI]) * 180.0 / M_PI;
    pt->dl = p[ROD_PAR_DL];
    pt->gamma = p[ROD_PAR_GAMMA];
    pt->dw = p[ROD_PAR_DW];
    pt->dz = isfinite(ob.dz) ? ob.dz : 0.0;
    pt->eig_even = rep->eig_even;
    pt->eig_odd = rep->eig_odd;
    pt->eig_scale = rep->scale;
    pt->parity_even = rep->parity_even;
    pt->parity_odd = rep->parity_odd;
    pt->residual_rel = rep->residual_rel;
    pt->outer_edges = b->r->fold_outer_edges;
    pt->n_negative = rep->n_negative;
    pt->iterations = rep->iterations;
}

static const rod_par dw_free[1] = {ROD_PAR_DW};

/* Step of the start's scan along a curve (the test function need not be monotone far from
 * Gamma*, so the start brackets its sign change before the secant takes over). */
#define SCAN_STEP 0.005

static rod_status search(rod_boundary *b, rod_crit_kind kind, int scan, double *p, char *why, size_t why_len);

/* The codim-2 point from the rod's state at p: the fold curve's point (free Delta W) followed in
 * Gamma by the secant on g_odd (search) to a step below 1e-8; with match_mesh re-located on the
 * mesh of the solution's Gamma (at most twice). rep is filled at the solution. */
/* Newton cap of the direct codim-2 solve before the fallback (measured: when it converges it
 * takes 5-10 iterations). */
#define DIRECT_CAP 10

/* A continuation that fails with the switch's Delta W below this and falling is named as the
 * boundary reaching Delta W = 0 (rod_boundary_move). */
#define DW_NEAR_ZERO 0.05

static int codim2_ok(const rod_crit_report *rep) { return rep->parity_even > 0.5 && rep->parity_odd < -0.5; }

static rod_status solve_codim2(rod_boundary *b, double *p, rod_crit_report *rep, int *direct)
{
    *direct = 0;
    if (b->o.direct && !b->o.match_mesh) {
        static const rod_par c2_free[2] = {ROD_PAR_DW, ROD_PAR_GAMMA};
        double pd[ROD_NPAR];
        memcpy(pd, p, sizeof pd);
        save_point(b, p, &b->trial);
        int old = rod_crit_set_cap(b->c, DIRECT_CAP);
        rod_status sd = rod_crit_solve(b->c, ROD_CRIT_CODIM2, c2_free, pd, rep, b->why, sizeof b->why);
        rod_crit_set_cap(b->c, old);
        if (sd == ROD_OK && codim2_ok(rep)) {
            memcpy(p, pd, sizeof pd);
            *direct = 1;
            return ROD_OK;
        }
        load_point(b, &b->trial);
        memcpy(p, b->trial.p, sizeof b->trial.p);
    }
    rod_status st = search(b, ROD_CRIT_FOLD, 0, p, b->msg, sizeof b->msg);
    for (int k = 0; st == ROD_OK && b->o.match_mesh && k < 2; k++) {
        int want = rod_mesh_outer_edges(b->r->n, p[ROD_PAR_GAMMA]);
        if (want == b->r->fold_outer_edges) break;
        remesh(b, p, want);
        st = search(b, ROD_CRIT_FOLD, 0, p, b->msg, sizeof b->msg);
    }
    if (st == ROD_OK) st = rod_crit_eval(b->c, p, rep, b->msg, sizeof b->msg);
    return st;
}


/* ---- start ---- */

/* Follows the curve of kind (free Delta W) in Gamma by secant steps on the other block's test
 * function toward its zero; returns with the rod near the codim-2 point. */
static rod_status search(rod_boundary *b, rod_crit_kind kind, int scan, double *p, char *why, size_t why_len)
{
    rod_crit_report rep;
    int other = kind == ROD_CRIT_PITCHFORK ? 0 : 1;
    rod_status st = rod_crit_solve(b->c, kind, dw_free, p, &rep, b->why, sizeof b->why);
    if (st != ROD_OK) {
        snprintf(why, why_len, "the start's %s did not converge as a critical point: %.150s",
                 kind == ROD_CRIT_FOLD ? "saddle-node" : "pitchfork", b->why);
        return st;
    }
    double G = other == 0 ? rep.g_even : rep.g_odd, gam = p[ROD_PAR_GAMMA];
    save_point(b, p, &b->scur);
    int have_prev = 0, away = 0, scanning = scan != 0;
    double slope = b->slope, step = 0.005;
    for (int k = 0; k < b->o.max_search; k++) {
        if (scanning) step = scan * SCAN_STEP;
        else if (isfinite(slope) && slope != 0.0) step = -G / slope;
        step = fmax(-b->o.gamma_step, fmin(b->o.gamma_step, step));
        if (!scanning && (fabs(step) < 1e-7 * fmax(1.0, rep.scale / 1e9) || fabs(G) < 1e-15 * rep.scale) && k > 0) {
            b->slope = slope;
            return ROD_OK;
        }
        double gn = gam + step;
        if (gn < b->o.gamma_min || gn > b->o.gamma_max) {
            snprintf(why, why_len, "codim-2 point not found: the search left the Gamma range [%g, %g] at Gamma %.4f "
                     "(the %s test function is %.3g there)", b->o.gamma_min, b->o.gamma_max, gam,
                     other == 0 ? "even" : "odd", G);
            return ROD_ERR_BRANCH_LOST;
        }
        double pn[ROD_NPAR];
        int ok = 0;
        for (int tries = 0; tries < 5 && !ok; tries++, step *= 0.5) {
            gn = gam + step;
            load_point(b, &b->scur);
            memcpy(pn, b->scur.p, sizeof pn);
            if (have_prev) {
                double f = step / (b->scur.p[ROD_PAR_GAMMA] - b->sprev.p[ROD_PAR_GAMMA]);
                for (int i = ROD_FREE_BEGIN; i < b->r->free_end; i++)
                    b->r->q[i] += f * (b->scur.snap.q[i] - b->sprev.snap.q[i]);
                pn[ROD_PAR_DW] += f * (b->scur.p[ROD_PAR_DW] - b->sprev.p[ROD_PAR_DW]);
            }
            pn[ROD_PAR_GAMMA] = gn;
            if (have_prev) rod_params_apply(b->r, pn);
            else remesh(b, pn, b->r->fold_outer_edges);
            ok = rod_crit_solve(b->c, kind, dw_free, pn, &rep, b->why, sizeof b->why) == ROD_OK;
        }
        if (!ok && !scanning && fabs(step) < 1e-5 * fmax(1.0, rep.scale / 1e9)) {
            /* Within 1e-5 of the root the solves sit at their round-off floor: the last point is it. */
            load_point(b, &b->scur);
            memcpy(p, b->scur.p, sizeof b->scur.p);
            b->slope = slope;
            return ROD_OK;
        }
        if (!ok) {
            snprintf(why, why_len, "codim-2 point not found: the %s curve could not be followed past Gamma %.4f: %.120s",
                     kind == ROD_CRIT_FOLD ? "saddle-node" : "pitchfork", gam, b->why);
            return ROD_ERR_BRANCH_LOST;
        }
        double Gn = other == 0 ? rep.g_even : rep.g_odd;
        slope = (Gn - G) / (gn - gam);
        away = (fabs(Gn) > fabs(G) && (Gn > 0) == (G > 0)) ? away + 1 : 0;
        if (scanning && (Gn > 0) != (G > 0)) scanning = 0; /* bracketed: secant from here */
        if (!scanning && away >= 3) {
            snprintf(why, why_len, "codim-2 point not found: along the %s curve the %s test function moves away from "
                     "zero (%.3g at Gamma %.4f): the two bifurcations do not meet from this start",
                     kind == ROD_CRIT_FOLD ? "saddle-node" : "pitchfork", other == 0 ? "even" : "odd", Gn, gn);
            return ROD_ERR_BRANCH_LOST;
        }
        bpoint_copy(&b->scur, &b->sprev);
        save_point(b, pn, &b->scur);
        have_prev = 1;
        G = Gn;
        gam = gn;
        memcpy(p, pn, sizeof pn);
    }
    snprintf(why, why_len, "codim-2 point not found: search cap of %d steps reached at Gamma %.4f", b->o.max_search, gam);
    return ROD_ERR_MAXITER;
}

rod_status rod_boundary_start(const rod_scene *scene, const rod_boundary_opts *o, rod_boundary **out_b,
                              rod_codim2_point *out, char *why, size_t why_len)
{
    *out_b = NULL;
    memset(out, 0, sizeof *out);
    rod_boundary *b = calloc(1, sizeof *b);
    if (!b) {
        snprintf(why, why_len, "out of memory");
        return ROD_ERR_ALLOC;
    }
    b->o = o ? *o : rod_boundary_opts_default();
    b->sc = *scene;
    b->sc.fold_angle_rel = 0.0;
    char key[64], msg[224];
    if (rod_scene_require_symmetric(&b->sc, msg, sizeof msg, key, sizeof key)) {
        free(b);
        snprintf(why, why_len, "%s: %s", key, msg);
        return ROD_ERR_SCENE;
    }
    if (b->sc.fold_angle_deg == 0.0) {
        free(b);
        snprintf(why, why_len, "the scene has no creases (folds.angle_deg = 0): there is no fold/pitchfork boundary");
        return ROD_ERR_SCENE;
    }
    b->sign = b->sc.fold_angle_deg < 0 ? -1.0 : 1.0;
    rod_status st = rod_alloc(&b->sc, &b->r, why, why_len);
    if (st != ROD_OK) {
        free(b);
        return st;
    }
    rod *r = b->r;
    b->k1 = malloc(sizeof(double) * (size_t)r->n);
    b->o.crit.tolerance = b->sc.tolerance;
    b->c = rod_crit_alloc(r, &b->o.crit);
    rod_solver *s = b->solver = rod_solver_alloc(r);
    if (!b->k1 || !b->c || !s || !bpoint_alloc(r, &b->cur) || !bpoint_alloc(r, &b->prev) ||
        !bpoint_alloc(r, &b->prev2) || !bpoint_alloc(r, &b->trial) || !bpoint_alloc(r, &b->scur) || !bpoint_alloc(r, &b->sprev) ||
        !bpoint_alloc(r, &b->mark)) {
        rod_boundary_free(b);
        snprintf(why, why_len, "out of memory");
        return ROD_ERR_ALLOC;
    }
    rod_route_report rr = {0};
    st = rod_route_to_state(r, s, &b->sc, +1, &rr);
    if (st != ROD_OK) {
        snprintf(why, why_len, "could not reach the upper state at Delta L = %g (%s, %.0f%% of the route done)",
                 b->sc.compression, rod_status_message(st), 100.0 * rr.reached);
        rod_boundary_free(b);
        return st;
    }
    rod_cont_opts co = b->o.cont;
    co.tolerance = b->sc.tolerance;
    co.max_negative = 2;
    rod_load load = {ROD_LOAD_SHEAR, b->sc.compression, 0.0};
    rod_tracer *t = rod_tracer_alloc(r, &load, &co);
    if (!t) {
        rod_boundary_free(b);
        snprintf(why, why_len, "out of memory");
        return ROD_ERR_ALLOC;
    }
    rod_branch br = {0};
    rod_trace_branch(t, 0.0, +1, &br);
    int ne, first = -1;
    const rod_event *ev = rod_tracer_events(t, &ne);
    for (int e = 0; e < ne; e++)
        if (ev[e].branch == 0 && ev[e].n_negative_before == 0) {
            first = e;
            break;
        }
    if (first < 0 || (ev[first].kind != ROD_EVENT_PITCHFORK && ev[first].kind != ROD_EVENT_SADDLE_NODE)) {
        snprintf(why, why_len, "codim-2 point not found: the primary branch has no pitchfork or saddle-node "
                 "instability from the start (%s; branch: %.120s)", first < 0 ? "none" : rod_event_name(ev[first].kind),
                 br.end_reason);
        rod_branch_free(&br);
        rod_tracer_free(t);
        rod_boundary_free(b);
        return ROD_ERR_BRANCH_LOST;
    }
    /* The start follows the fold curve (regular through Gamma*, g_odd crossing zero on it
     * linearly). With the pitchfork first, the fold is the next event, and there the odd block
     * has one negative eigenvalue, the pitchfork's mode continued: its bordering vector is found
     * by shift-invert iteration below it (the most negative of a few shifts), since the odd
     * mode nearest zero may be another one. */
    int pf = -1;
    if (ev[first].kind == ROD_EVENT_PITCHFORK) {
        pf = first;
        first = -1;
        for (int e = pf + 1; e < ne; e++)
            if (ev[e].branch == 0 && ev[e].kind == ROD_EVENT_SADDLE_NODE) {
                first = e;
                break;
            }
        if (first < 0) {
            snprintf(why, why_len, "codim-2 point not found: no saddle-node on the primary branch after its pitchfork "
                     "(branch: %.150s)", br.end_reason);
            rod_branch_free(&br);
            rod_tracer_free(t);
            rod_boundary_free(b);
            return ROD_ERR_BRANCH_LOST;
        }
    }
    const rod_crit_kind kind = ROD_CRIT_FOLD;
    double p[ROD_NPAR];
    p[ROD_PAR_DW] = rod_tracer_event_state(t, first);
    p[ROD_PAR_GAMMA] = b->sc.fold_position;
    p[ROD_PAR_PHI] = b->sc.fold_angle_deg * M_PI / 180.0;
    p[ROD_PAR_DL] = b->sc.compression;
    rod_crit_report rep;
    st = rod_crit_modes(b->c, p, &rep, b->why, sizeof b->why);
    const double *mode = rod_tracer_mode(t, first);
    if (st == ROD_OK && mode) rod_crit_set_mode(b->c, 1, mode);
    const double *pmode = pf >= 0 ? rod_tracer_mode(t, pf) : NULL;
    if (st == ROD_OK && pmode) {
        double scale = fabs(rep.eig_even) + fabs(rep.eig_odd) + 1e-12, best = INFINITY, bs = NAN, e1;
        for (int k = 0; k < 4 && st == ROD_OK; k++) {
            double sigma = -scale * pow(10.0, k - 1);
            if ((st = rod_crit_refine_mode(b->c, p, -1, pmode, sigma, &e1)) == ROD_OK && e1 < best) {
                best = e1;
                bs = sigma;
            }
        }
        if (st == ROD_OK) st = rod_crit_refine_mode(b->c, p, -1, pmode, bs, &e1);
    }
    rod_branch_free(&br);
    rod_tracer_free(t);
    *out_b = b;
    if (st != ROD_OK) {
        snprintf(why, why_len, "critical modes at the first event: %.150s", b->why);
        return st;
    }
    b->slope = NAN;
    save_point(b, p, &b->trial);
    char msg1[400];
    st = search(b, kind, pf >= 0 ? +1 : -1, p, msg1, sizeof msg1);
    if (st != ROD_OK) {
        load_point(b, &b->trial);
        memcpy(p, b->trial.p, sizeof b->trial.p);
        st = search(b, kind, pf >= 0 ? -1 : +1, p, why, why_len);
        if (st != ROD_OK) {
            size_t k = strlen(why);
            snprintf(why + k, why_len - k, "; the other way: %.150s", msg1);
            return st;
        }
    }
    st = rod_crit_eval(b->c, p, &rep, b->msg, sizeof b->msg);
    if (st != ROD_OK || !codim2_ok(&rep)) {
        if (st == ROD_OK)
            snprintf(why, why_len, "codim-2 point not found: the critical modes at Gamma %.4f have parities %.2f and %.2f, "
                     "not one even and one odd", p[ROD_PAR_GAMMA], rep.parity_even, rep.parity_odd);
        else
            snprintf(why, why_len, "%.300s", b->msg);
        return st != ROD_OK ? st : ROD_ERR_BRANCH_LOST;
    }
    if (p[ROD_PAR_GAMMA] < b->o.gamma_min || p[ROD_PAR_GAMMA] > b->o.gamma_max) {
        snprintf(why, why_len, "the codim-2 point Gamma* = %.4f lies outside the Gamma range [%g, %g]", p[ROD_PAR_GAMMA],
                 b->o.gamma_min, b->o.gamma_max);
        return ROD_ERR_BRANCH_LOST;
    }
    save_point(b, p, &b->cur);
    fill_info(b, p, &rep, &b->cur.info);
    *out = b->cur.info;
    rod_crit_update_borders(b->c, p);
    load_point(b, &b->cur);
    return ROD_OK;
}

/* ---- continuation in phi or Delta L ---- */

/* 1 when the first instability of the primary branch at (phi, Gamma* - 1e-3, Delta L) of pt lies
 * within 0.02 of pt's Delta W (see rod_boundary.h); *first_dw gets it (0 when none). */
static int is_regime_boundary(const rod_boundary *b, const rod_codim2_point *pt, double *first_dw)
{
    rod_scene sc = b->sc;
    sc.fold_angle_deg = b->sign * pt->phi_deg;
    sc.fold_position = pt->gamma - 1e-3;
    sc.compression = pt->dl;
    rod_analysis_opts o = rod_analysis_opts_classify();
    rod_analysis a;
    char err[256];
    *first_dw = 0.0;
    if (rod_bifurcation_analyse(&sc, &o, &a, err, sizeof err) != ROD_OK) return 1; /* cannot tell: keep */
    int ok = 1;
    if (a.first >= 0) {
        *first_dw = a.events[a.first].at.dw;
        ok = fabs(*first_dw - pt->dw) <= 0.02;
    }
    rod_analysis_free(&a);
    return ok;
}

static int append_c2(rod_boundary_curve *c, const rod_codim2_point *pt)
{
    if (c->n == c->cap) {
        size_t cap = c->cap ? 2 * c->cap : 32;
        rod_codim2_point *np = realloc(c->pts, cap * sizeof *np);
        if (!np) return 0;
        c->pts = np;
        c->cap = cap;
    }
    c->pts[c->n++] = *pt;
    return 1;
}

rod_status rod_boundary_move(rod_boundary *b, rod_par par, double target, rod_boundary_curve *rec)
{
    char reason[256] = "";
    rod_status st = ROD_OK;
    double tv = par == ROD_PAR_PHI ? b->sign * target * M_PI / 180.0 : target;
    double h0 = par == ROD_PAR_PHI ? b->o.phi_step_deg * M_PI / 180.0 : b->o.dl_step, h = h0;
    const char *pname = par == ROD_PAR_PHI ? "phi" : "Delta L";
    /* The secant carries over from a previous move in the same parameter that ended here. */
    int have_prev = b->prev_valid && b->prev_par == par;
    int have_prev2 = have_prev && b->prev2_valid;
    const int quadratic = b->o.predictor >= 2;
    /* The spacing of the regime-boundary checks carries over too. */
    double last_check = b->check_valid && b->check_par == par ? b->last_check : b->cur.p[par], check_step = par == ROD_PAR_PHI ? b->o.verify_every * M_PI / 180.0
                                                                        : b->o.verify_every / 100.0;
    if (par == ROD_PAR_PHI && !(target > 0.0 && target < 180.0)) {
        snprintf(reason, sizeof reason, "phi %g deg is outside (0, 180): the creases vanish or close there", target);
        st = ROD_ERR_SCENE;
    }
    if (par == ROD_PAR_DL && !(target > 0.0 && target < 1.0)) {
        snprintf(reason, sizeof reason, "Delta L %g is outside (0, 1)", target);
        st = ROD_ERR_SCENE;
    }
    int p1_old = rod_crit_set_phase1_cap(b->c, b->o.phase1_cap);
    for (int steps = 0; st == ROD_OK; steps++) {
        double cv = b->cur.p[par], left = tv - cv;
        if (fabs(left) <= 1e-12) {
            snprintf(reason, sizeof reason, "reached %s = %g", pname, target);
            break;
        }
        if (steps >= b->o.max_steps) {
            snprintf(reason, sizeof reason, "step cap %d reached at %s = %g", b->o.max_steps, pname,
                     par == ROD_PAR_PHI ? b->cur.info.phi_deg : cv);
            st = ROD_ERR_MAXITER;
            break;
        }
        double hh = fmin(h, fabs(left)) * (left > 0 ? 1.0 : -1.0), pn[ROD_NPAR];
        load_point(b, &b->cur);
        memcpy(pn, b->cur.p, sizeof pn);
        if (quadratic && have_prev2 && b->prev2.n_out == b->cur.n_out && b->prev.n_out == b->cur.n_out) {
            /* Quadratic predictor through the last three points (Lagrange weights at cv + hh):
             * its error is O(h^3) against the secant's O(h^2), so the corrector starts closer and
             * the step can stay long. */
            double s0 = b->prev2.p[par], s1 = b->prev.p[par], s2 = cv, x = cv + hh;
            double w2 = (x - s1) * (x - s0) / ((s2 - s1) * (s2 - s0));
            double w1 = (x - s2) * (x - s0) / ((s1 - s2) * (s1 - s0));
            double w0 = (x - s2) * (x - s1) / ((s0 - s2) * (s0 - s1));
            for (int i = ROD_FREE_BEGIN; i < b->r->free_end; i++)
                b->r->q[i] = w2 * b->cur.snap.q[i] + w1 * b->prev.snap.q[i] + w0 * b->prev2.snap.q[i];
            pn[ROD_PAR_DW] = w2 * b->cur.p[ROD_PAR_DW] + w1 * b->prev.p[ROD_PAR_DW] + w0 * b->prev2.p[ROD_PAR_DW];
            pn[ROD_PAR_GAMMA] =
                w2 * b->cur.p[ROD_PAR_GAMMA] + w1 * b->prev.p[ROD_PAR_GAMMA] + w0 * b->prev2.p[ROD_PAR_GAMMA];
        } else if (have_prev && b->prev.n_out == b->cur.n_out) {
            double f = hh / (b->cur.p[par] - b->prev.p[par]);
            for (int i = ROD_FREE_BEGIN; i < b->r->free_end; i++)
                b->r->q[i] += f * (b->cur.snap.q[i] - b->prev.snap.q[i]);
            pn[ROD_PAR_DW] += f * (b->cur.p[ROD_PAR_DW] - b->prev.p[ROD_PAR_DW]);
            pn[ROD_PAR_GAMMA] += f * (b->cur.p[ROD_PAR_GAMMA] - b->prev.p[ROD_PAR_GAMMA]);
        }
        pn[par] = cv + hh;
        rod_params_apply(b->r, pn);
        rod_crit_report rep;
        int direct = 0;
        rod_status s2 = solve_codim2(b, pn, &rep, &direct);
        if (s2 == ROD_OK && !codim2_ok(&rep)) {
            s2 = ROD_ERR_BRANCH_LOST;
            snprintf(b->msg, sizeof b->msg, "modes of parity %.2f and %.2f", rep.parity_even, rep.parity_odd);
        }
        if (s2 != ROD_OK) {
            h *= 0.5;
            if (h < b->o.min_step_frac * h0) {
                double at = par == ROD_PAR_PHI ? fabs(cv) * 180.0 / M_PI : cv;
                double dw1 = b->cur.p[ROD_PAR_DW], dw0 = have_prev ? b->prev.p[ROD_PAR_DW] : dw1;
                double dpar = have_prev ? b->cur.p[par] - b->prev.p[par] : 0.0;
                if (have_prev && dw1 < DW_NEAR_ZERO && dw1 < dw0 && dpar * (tv - cv) > 0.0) {
                    /* The switch's Delta W runs to zero: past it the two bifurcations would meet
                     * before any shear, and there is no codim-2 point of the sheared branch. It
                     * ends as a square root (Delta W^2 linear in phi: 0.00303 per deg over the
                     * last 3 deg at Delta L 0.3, N = 61), so the end is extrapolated in Delta W^2;
                     * a straight line in Delta W overshoots, by more the longer the last step. */
                    double z = b->cur.p[par] + dpar * dw1 * dw1 / (dw0 * dw0 - dw1 * dw1);
                    snprintf(reason, sizeof reason,
                             "the codim-2 point's Delta W runs to 0 at %s = %.6g (extrapolated; %.4f at %s = %.6g, "
                             "the last point): beyond it the switch would need a negative shear, so the boundary of "
                             "the sheared branch ends there",
                             pname, par == ROD_PAR_PHI ? fabs(z) * 180.0 / M_PI : z, dw1, pname, at);
                    st = ROD_ERR_BRANCH_LOST;
                    continue;
                }
                snprintf(reason, sizeof reason, "the codim-2 point could not be continued past %s = %.6g: %.150s", pname,
                         at, b->msg);
                st = s2;
            }
            continue;
        }
        if (pn[ROD_PAR_GAMMA] < b->o.gamma_min || pn[ROD_PAR_GAMMA] > b->o.gamma_max) {
            snprintf(reason, sizeof reason,
                     "the boundary left the Gamma range [%g, %g] between %s = %.6g and %.6g (Gamma* %.4f there)",
                     b->o.gamma_min, b->o.gamma_max, pname, par == ROD_PAR_PHI ? fabs(cv) * 180.0 / M_PI : cv,
                     par == ROD_PAR_PHI ? fabs(pn[par]) * 180.0 / M_PI : pn[par], pn[ROD_PAR_GAMMA]);
            st = ROD_ERR_BRANCH_LOST;
            break;
        }
        if (rep.n_negative != 0) {
            snprintf(reason, sizeof reason,
                     "at %s = %.6g (Gamma* %.4f) %d other eigenvalue%s already negative at the codim-2 point: an "
                     "earlier instability decides the snap there, this is no longer the regime boundary",
                     pname, par == ROD_PAR_PHI ? fabs(pn[par]) * 180.0 / M_PI : pn[par], pn[ROD_PAR_GAMMA],
                     rep.n_negative, rep.n_negative == 1 ? " is" : "s are");
            st = ROD_ERR_BRANCH_LOST;
            break;
        }
        if (b->o.verify_every > 0.0 && (fabs(pn[par] - last_check) >= check_step || (b->o.verify_ends && fabs(tv - pn[par]) <= 1e-12))) {
            rod_codim2_point chk;
            fill_info(b, pn, &rep, &chk);
            double fdw;
            if (!is_regime_boundary(b, &chk, &fdw)) {
                snprintf(reason, sizeof reason,
                         "at %s = %.6g the codim-2 point (Gamma* %.4f, Delta W %.4f) is no longer the regime boundary: "
                         "just below it the first instability is at Delta W %.4f",
                         pname, par == ROD_PAR_PHI ? chk.phi_deg : pn[par], chk.gamma, chk.dw, fdw);
                st = ROD_ERR_BRANCH_LOST;
                break;
            }
            last_check = pn[par]; /* the check builds its own rod: this one still holds the point */
        }
        if (have_prev) bpoint_copy(&b->prev, &b->prev2);
        have_prev2 = have_prev;
        bpoint_copy(&b->cur, &b->prev);
        have_prev = 1;
        save_point(b, pn, &b->cur);
        fill_info(b, pn, &rep, &b->cur.info);
        b->cur.info.direct = direct;
        rod_crit_update_borders(b->c, pn);
        if (rec && !append_c2(rec, &b->cur.info)) {
            snprintf(reason, sizeof reason, "out of memory");
            st = ROD_ERR_ALLOC;
            break;
        }
        if (rep.iterations <= (direct ? 10 : 5)) h = fmin(1.5 * h, h0);
    }
    rod_crit_set_phase1_cap(b->c, p1_old);
    load_point(b, &b->cur);
    b->prev_valid = have_prev;
    b->prev2_valid = have_prev2;
    b->prev_par = par;
    b->check_valid = 1;
    b->check_par = par;
    b->last_check = last_check;
    if (rec) {
        rec->end_status = st;
        snprintf(rec->end_reason, sizeof rec->end_reason, "%s", reason);
    }
    return st;
}

int rod_boundary_check(const rod_boundary *b, double *first_dw)
{
    return is_regime_boundary(b, &b->cur.info, first_dw);
}

/* ---- fold and pitchfork curves ---- */

static int append_cc(rod_crit_curve *c, const rod_crit_curve_point *pt)
{
    if (c->n == c->cap) {
        size_t cap = c->cap ? 2 * c->cap : 32;
        rod_crit_curve_point *np = realloc(c->pts, cap * sizeof *np);
        if (!np) return 0;
        c->pts = np;
        c->cap = cap;
    }
    c->pts[c->n++] = *pt;
    return 1;
}

static void curve_point(rod_boundary *b, rod_crit_kind kind, const double *p, const rod_crit_report *rep,
                        rod_crit_curve_point *pt)
{
    rod_obs ob;
    rod_observe(b->r, b->k1, &ob);
    pt->gamma = p[ROD_PAR_GAMMA];
    pt->dw = p[ROD_PAR_DW];
    pt->dz = isfinite(ob.dz) ? ob.dz : 0.0;
    pt->g_other = kind == ROD_CRIT_FOLD ? rep->g_odd : rep->g_even;
}

static int cmp_gamma(const void *a, const void *b)
{
    double x = ((const rod_crit_curve_point *)a)->gamma, y = ((const rod_crit_curve_point *)b)->gamma;
    return (x > y) - (x < y);
}

/* One try of the curve point at Gamma gn from b->cur (secant from b->prev when have_prev). */
static rod_status curve_try(rod_boundary *b, rod_crit_kind kind, int have_prev, double gn, double *pn,
                            rod_crit_report *rep)
{
    load_point(b, &b->cur);
    memcpy(pn, b->cur.p, sizeof(double) * ROD_NPAR);
    double step = gn - b->cur.p[ROD_PAR_GAMMA];
    if (have_prev && b->prev.n_out == b->cur.n_out) {
        double f = step / (b->cur.p[ROD_PAR_GAMMA] - b->prev.p[ROD_PAR_GAMMA]);
        for (int i = ROD_FREE_BEGIN; i < b->r->free_end; i++) b->r->q[i] += f * (b->cur.snap.q[i] - b->prev.snap.q[i]);
        pn[ROD_PAR_DW] += f * (b->cur.p[ROD_PAR_DW] - b->prev.p[ROD_PAR_DW]);
    }
    pn[ROD_PAR_GAMMA] = gn;
    int want = b->o.match_mesh ? rod_mesh_outer_edges(b->r->n, gn) : b->r->fold_outer_edges;
    if (!have_prev || b->prev.n_out != b->cur.n_out || want != b->r->fold_outer_edges) {
        /* No secant on this mesh: carry the state along the rod to the new Gamma. */
        load_point(b, &b->cur);
        memcpy(pn, b->cur.p, sizeof(double) * ROD_NPAR);
        pn[ROD_PAR_GAMMA] = gn;
        remesh(b, pn, want);
    } else {
        rod_params_apply(b->r, pn);
    }
    return rod_crit_solve(b->c, kind, dw_free, pn, rep, b->why, sizeof b->why);
}

rod_status rod_boundary_crit_curve(rod_boundary *b, rod_crit_kind kind, double gamma_lo, double gamma_hi,
                                   double dgamma, rod_crit_curve *out)
{
    memset(out, 0, sizeof *out);
    out->end_status = ROD_OK;
    snprintf(out->end_reason, sizeof out->end_reason, "covered Gamma %g .. %g", gamma_lo, gamma_hi);
    if (!(dgamma > 0.0) || !(gamma_hi > gamma_lo)) {
        snprintf(out->end_reason, sizeof out->end_reason, "empty Gamma range");
        return out->end_status = ROD_ERR_SCENE;
    }
    bpoint_copy(&b->cur, &b->trial); /* the codim-2 point, restored at the end */
    rod_crit_curve_point pt;
    load_point(b, &b->cur);
    {
        rod_crit_report rep;
        double p0[ROD_NPAR];
        memcpy(p0, b->cur.p, sizeof p0);
        if (rod_crit_eval(b->c, p0, &rep, NULL, 0) == ROD_OK) {
            curve_point(b, kind, p0, &rep, &pt);
            if (!append_cc(out, &pt)) return out->end_status = ROD_ERR_ALLOC;
        }
    }
    double gstar = b->cur.p[ROD_PAR_GAMMA];
    rod_status worst = ROD_OK;
    for (int dir = -1; dir <= 1; dir += 2) {
        bpoint_copy(&b->trial, &b->cur);
        int have_prev = 0;
        double k0 = floor((gstar - gamma_lo) / dgamma);
        for (int k = 0;; k++) {
            double gn = dir < 0 ? gamma_lo + (k0 - k) * dgamma : gamma_lo + (k0 + 1 + k) * dgamma;
            if (dir < 0 && gn >= gstar - 1e-12) continue;
            if (gn < gamma_lo - 1e-12 || gn > gamma_hi + 1e-12) break;
            double pn[ROD_NPAR];
            rod_crit_report rep;
            /* Substeps toward gn, halved on failure (to 1/256 of the grid step), grown after a
             * success; the secant predictor uses the last two accepted substeps. */
            rod_status st = ROD_OK;
            double h = dgamma;
            while (fabs(gn - b->cur.p[ROD_PAR_GAMMA]) > 1e-12) {
                double left = gn - b->cur.p[ROD_PAR_GAMMA], gs = fabs(left) <= h ? gn : b->cur.p[ROD_PAR_GAMMA] + copysign(h, left);
                st = curve_try(b, kind, have_prev, gs, pn, &rep);
                if (st != ROD_OK) {
                    h *= 0.5;
                    if (h < dgamma / 256.0) break;
                    continue;
                }
                if (gs != gn) {
                    bpoint_copy(&b->cur, &b->prev);
                    save_point(b, pn, &b->cur);
                    have_prev = 1;
                    h = fmin(2.0 * h, dgamma);
                } else {
                    break;
                }
            }
            if (st != ROD_OK) {
                snprintf(out->end_reason, sizeof out->end_reason, "the %s curve could not be followed past Gamma %.4f: %.150s",
                         kind == ROD_CRIT_FOLD ? "saddle-node" : "pitchfork", b->cur.p[ROD_PAR_GAMMA], b->why);
                worst = st;
                break;
            }
            bpoint_copy(&b->cur, &b->prev);
            save_point(b, pn, &b->cur);
            have_prev = 1;
            curve_point(b, kind, pn, &rep, &pt);
            if (!append_cc(out, &pt)) return out->end_status = ROD_ERR_ALLOC;
        }
    }
    bpoint_copy(&b->trial, &b->cur);
    load_point(b, &b->cur);
    b->prev_valid = b->prev2_valid = 0; /* prev held the curve's points: no secant from them */
    qsort(out->pts, out->n, sizeof *out->pts, cmp_gamma);
    out->end_status = worst;
    return worst;
}
