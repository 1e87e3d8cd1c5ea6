/* sim_sweep_task.c: a row task of the sweep (see sim_sweep_task.h). */
#include "sim_sweep_task.h"

#include "rod_bifurcation.h"
#include "rod_route.h"
#include "rod_seed.h"
#include "rod_seed_fold.h"
#include "rod_solver.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int sweep_is_regime(const sweep_row *r)
{
    return !strcmp(r->regime, "asymmetric") || !strcmp(r->regime, "symmetric") || !strcmp(r->regime, "none");
}

/* An upper state and how it was reached. */
typedef struct upper {
    rod *r;              /* NULL: not reached */
    rod_scene sc;        /* its scene */
    double wall_s;       /* s spent reaching it */
    char how[12];        /* route / continued */
    char why[320];       /* when not reached: the evidence */
    int lost;            /* not reached, and both paths lost it as a stable state */
    double lost_at;      /* Gamma of the last stable state continuation reached */
    int nfold;           /* critical points located where continuation toward this point ended */
    int fold_pf[2];      /* (at most 2, one from each side): 0 fold, 1 pitchfork; their Gamma, */
    double fold_at[2];
    double fold_from[2]; /* the Gamma each continuation came from, */
    double fold_eig[2];  /* the critical block's eigenvalue at the last state there (E I1 / l^2) */
    double fold_rel[2];  /* and at the fold, over max |K_ii| */
} upper;

typedef struct row_task {
    const sweep_spec *sp;
    double phi, dl;
    const sweep_table *known;
    sweep_table mine;    /* classifications of this task */
    sweep_emit_fn emit;
    void *ctx;
    const volatile sig_atomic_t *cancel;
    rod_solver *s;       /* shared by every rod of the task (same node count) */
} row_task;

rod_scene sweep_scene_at(const sweep_spec *sp, double phi, double gamma, double dl)
{
    rod_scene sc = sp->base;
    sc.fold_angle_rel = 0.0; /* the analysis traces the perfect scene (rod_bifurcation.h) */
    sc.fold_angle_deg = sp->sign * phi;
    sc.fold_position = gamma;
    sc.compression = dl;
    return sc;
}

static rod_scene scene_at(const row_task *t, double gamma) { return sweep_scene_at(t->sp, t->phi, gamma, t->dl); }

int sweep_grid_check(const sweep_spec *sp, const double *phi, int nphi, const double *dl, int ndl, char *why,
                     size_t why_len)
{
    for (int k = 0; k < ndl; k++)
        for (int i = 0; i < nphi; i++)
            for (int j = 0; j < sp->ngamma; j++) {
                rod_scene sc = sweep_scene_at(sp, phi[i], sp->gamma[j], dl[k]);
                char msg[256] = "", key[64] = "";
                if (rod_scene_check(&sc, msg, sizeof msg, key, sizeof key) != 0) {
                    snprintf(why, why_len, "phi %g deg, Gamma %g, Delta L %g: %s: %s", phi[i], sp->gamma[j], dl[k],
                             key, msg);
                    return -1;
                }
            }
    return 0;
}

/* A point the mesh cannot hold (rod_scene_check on u->sc): 1 with its own reason in u->why (not
 * a path that failed, and not "lost"), else 0. */
static int unfit(upper *u)
{
    char msg[160], key[64];
    if (rod_scene_check(&u->sc, msg, sizeof msg, key, sizeof key) == 0) return 0;
    snprintf(u->why, sizeof u->why, "%s: %s", key, msg);
    u->lost = 0;
    return 1;
}

static void by_route(row_task *t, upper *u, double gamma)
{
    double t0 = now();
    u->sc = scene_at(t, gamma);
    if (unfit(u)) return;
    u->r = NULL;
    rod *r = NULL;
    char err[160] = "";
    rod_status st = rod_alloc(&u->sc, &r, err, sizeof err);
    if (st == ROD_OK) {
        rod_route_report rep = {0};
        st = rod_route_to_state(r, t->s, &u->sc, +1, &rep);
        if (st == ROD_OK && rod_seed_is_stable(r) == 0) {
            st = ROD_ERR_BRANCH_LOST;
            snprintf(err, sizeof err, "route: its state at Delta W = 0 is unstable (a negative eigenvalue)");
            rod_free(r);
        } else if (st == ROD_OK) {
            u->r = r;
            snprintf(u->how, sizeof u->how, "route");
        } else {
            snprintf(err, sizeof err, "route: %s", rod_status_message(st));
            rod_free(r);
        }
    }
    if (!u->r) {
        size_t len = strlen(u->why);
        snprintf(u->why + len, sizeof u->why - len, "%s%s", len ? "; " : "", err);
        u->lost = u->lost && st == ROD_ERR_BRANCH_LOST;
    }
    u->wall_s += now() - t0;
}

/* From the solved state `from` to gamma by continuation; on failure the evidence goes to u->why. */
static void by_continuation(row_task *t, const upper *from, upper *u, double gamma)
{
    double t0 = now();
    u->sc = scene_at(t, gamma);
    if (unfit(u)) return;
    rod_seed_report rep;
    rod *last = NULL;
    rod_scene last_sc;
    rod_status st = rod_seed_continue_keep(from->r, &from->sc, &u->sc, t->s, &u->r, &rep, &last, &last_sc);
    if (st == ROD_OK) {
        snprintf(u->how, sizeof u->how, "continued");
    } else {
        u->lost = st == ROD_ERR_BRANCH_LOST;
        u->lost_at = rep.gamma_reached;
        snprintf(u->why, sizeof u->why, "continued from Gamma %.4g: lost at Gamma %.4g (lowest eigenvalue %.3g -> %.3g)",
                 from->sc.fold_position, rep.gamma_reached, rep.eig_start, rep.eig_last);
        /* Where continuation stopped, the fold that ends the state, located directly (Gamma free,
         * Delta W = 0; rod_seed_fold.h): the evidence that the upper state does not exist at
         * this point, rather than a path that failed. */
        rod_seed_fold_report fr;
        if (last && u->nfold < 2 && rod_seed_fold_locate(last, &last_sc, &u->sc, &fr) == ROD_OK && fr.located) {
            int k = u->nfold++;
            u->fold_pf[k] = fr.pitchfork;
            u->fold_at[k] = fr.at;
            u->fold_from[k] = from->sc.fold_position;
            u->fold_eig[k] = fr.eig_from;
            u->fold_rel[k] = fr.eig_rel;
            u->lost = 1;
            u->lost_at = fr.at;
        }
    }
    rod_free(last);
    u->wall_s += now() - t0;
}

static void upper_free(upper *u)
{
    rod_free(u->r);
    u->r = NULL;
}

/* The upper state at every grid Gamma (step 1 of the task). */
static void chain(row_task *t, upper *ups)
{
    int ng = t->sp->ngamma, j0 = (ng - 1) / 2, anchor = -1;
    for (int j = 0; j < ng; j++) {
        memset(&ups[j], 0, sizeof ups[j]);
        ups[j].lost = 1;
    }
    if (t->sp->seed_route) {
        for (int j = 0; j < ng && !*t->cancel; j++) by_route(t, &ups[j], t->sp->gamma[j]);
        return;
    }
    /* Anchor: the middle, then alternately above and below it. */
    for (int k = 0; k < 2 * ng && anchor < 0 && !*t->cancel; k++) {
        int j = j0 + (k % 2 ? (k + 1) / 2 : -(k / 2));
        if (j < 0 || j >= ng || ups[j].why[0]) continue;
        by_route(t, &ups[j], t->sp->gamma[j]);
        if (ups[j].r) anchor = j;
    }
    if (anchor < 0) return;
    for (int dir = -1; dir <= 1; dir += 2) {
        int last = anchor;
        for (int j = anchor + dir; j >= 0 && j < ng && !*t->cancel; j += dir) {
            if (ups[j].r) { last = j; continue; }
            ups[j].why[0] = '\0';
            ups[j].lost = 1;
            by_continuation(t, &ups[last], &ups[j], t->sp->gamma[j]);
            if (!ups[j].r) by_route(t, &ups[j], t->sp->gamma[j]);
            if (ups[j].r) last = j;
        }
    }
    /* Another path to the points still unreached: continuation back from the next solved point
     * beyond them (away from the anchor), when there is one. */
    for (int j = 0; j < ng && !*t->cancel; j++) {
        rod_scene sc = scene_at(t, t->sp->gamma[j]);
        if (ups[j].r || rod_scene_check(&sc, NULL, 0, NULL, 0) != 0) continue;
        int dir = j < anchor ? -1 : 1, k = j + dir;
        while (k >= 0 && k < ng && !ups[k].r) k += dir;
        if (k < 0 || k >= ng) continue;
        upper back;
        memset(&back, 0, sizeof back);
        by_continuation(t, &ups[k], &back, t->sp->gamma[j]);
        if (back.r) {
            back.wall_s += ups[j].wall_s;
            snprintf(back.how, sizeof back.how, "continued");
            ups[j] = back;
        } else {
            size_t len = strlen(ups[j].why);
            snprintf(ups[j].why + len, sizeof ups[j].why - len, "; back from %.4g: lost at %.4g",
                     ups[k].sc.fold_position, back.lost_at);
            ups[j].wall_s += back.wall_s;
            ups[j].lost = ups[j].lost && back.lost;
            for (int f = 0; f < back.nfold && ups[j].nfold < 2; f++) {
                int q = ups[j].nfold++;
                ups[j].fold_pf[q] = back.fold_pf[f];
                ups[j].fold_at[q] = back.fold_at[f];
                ups[j].fold_from[q] = back.fold_from[f];
                ups[j].fold_eig[q] = back.fold_eig[f];
                ups[j].fold_rel[q] = back.fold_rel[f];
            }
        }
    }
}

static void row_init(const row_task *t, sweep_row *row, char kind, double gamma)
{
    memset(row, 0, sizeof *row);
    row->kind = kind;
    row->phi = t->phi;
    row->dl = t->dl;
    row->gamma = row->gamma_lo = row->gamma_hi = gamma;
    snprintf(row->upper, sizeof row->upper, "-");
}

/* Classifies from the upper state u into row. */
static void classify(const upper *u, sweep_row *row)
{
    double t0 = now();
    snprintf(row->first_type, sizeof row->first_type, "none");
    if (!u->r) {
        /* A located fold on the way is the evidence of "no upper state" whatever else failed (the
         * route's Newton cap there is the same missing state). */
        snprintf(row->regime, sizeof row->regime, "%s", u->lost || u->nfold ? "no-upper" : "failed");
        static const char *const what[2] = {"fold", "pitchfork"};
        const char *route = strstr(u->why, "; route");
        if (u->nfold == 1) {
            /* A fold: the state ends there; a pitchfork (odd mode): it goes on past it, unstable. */
            snprintf(row->note, sizeof row->note,
                     "%s at Gamma %.6f (continued from %.4g; Delta W 0; %s eigenvalue %.2g -> %.1e max|K_ii|)%s%.50s",
                     what[u->fold_pf[0]], u->fold_at[0], u->fold_from[0], u->fold_pf[0] ? "odd" : "even", u->fold_eig[0],
                     u->fold_rel[0], route ? "; " : "", route ? route + 2 : "");
        } else if (u->nfold == 2) {
            snprintf(row->note, sizeof row->note,
                     "%s at Gamma %.6f and %s at Gamma %.6f (continued from %.4g and %.4g; Delta W 0; eigenvalue -> %.1e max|K_ii|)",
                     what[u->fold_pf[0]], u->fold_at[0], what[u->fold_pf[1]], u->fold_at[1], u->fold_from[0], u->fold_from[1],
                     fmax(u->fold_rel[0], u->fold_rel[1]));
        } else {
            snprintf(row->note, sizeof row->note, "%.159s", u->why[0] ? u->why : "the upper state was not reached");
        }
        row->wall_s = u->wall_s;
        return;
    }
    snprintf(row->upper, sizeof row->upper, "%s", u->how);
    rod_analysis_opts o = rod_analysis_opts_classify();
    rod_analysis a;
    char err[160] = "";
    rod_status st = rod_bifurcation_analyse_from(&u->sc, &o, u->r, &a, err, sizeof err);
    if (st != ROD_OK) {
        snprintf(row->regime, sizeof row->regime, "failed");
        snprintf(row->note, sizeof row->note, "%s", err[0] ? err : rod_status_message(st));
    } else {
        snprintf(row->regime, sizeof row->regime, "%s", a.regime);
        if (a.first >= 0) {
            const rod_event *e = &a.events[a.first];
            snprintf(row->first_type, sizeof row->first_type, "%s", rod_event_name(e->kind));
            row->first_dw = e->at.dw;
            row->first_dz = e->at.dz;
        } else {
            snprintf(row->note, sizeof row->note, "%.150s", a.branches[0].end_reason);
        }
        rod_analysis_free(&a);
    }
    row->wall_s = u->wall_s + (now() - t0);
}

static void emit(row_task *t, const sweep_row *row, int is_new)
{
    if ((row->kind == 'p' || row->kind == 'q') && !sweep_table_find(&t->mine, row->phi, row->gamma, row->dl))
        sweep_table_add(&t->mine, row);
    t->emit(t->ctx, row, is_new);
}

/* A known classification (from the file or this task), or NULL. */
static const sweep_row *known_row(const row_task *t, double gamma)
{
    const sweep_row *k = sweep_table_find(&t->mine, t->phi, gamma, t->dl);
    return k ? k : sweep_table_find(t->known, t->phi, gamma, t->dl);
}

/* A probe's classification at gamma, its upper state continued from `from` (else the route). */
static void probe(row_task *t, const upper *from, double gamma, sweep_row *row)
{
    const sweep_row *k = known_row(t, gamma);
    if (k) {
        *row = *k;
        return;
    }
    upper u;
    memset(&u, 0, sizeof u);
    u.lost = 1;
    if (from && from->r) by_continuation(t, from, &u, gamma);
    if (!u.r) by_route(t, &u, gamma);
    row_init(t, row, 'q', gamma);
    classify(&u, row);
    upper_free(&u);
    emit(t, row, 1);
}

/* Bisects one grid cell (step 3). A midpoint of a third regime (a narrow band inside the cell,
 * such as "none" between the two snaps) splits the cell: the upper part is pushed and bisected
 * after the lower one, so each boundary gets its own row (at most 8 parts per cell). */
static void bisect_cell(row_task *t, const upper *from, const sweep_row *rlo, const sweep_row *rhi)
{
    struct part {
        double lo, hi;
        char rlo[16], rhi[16];
    } stack[8];
    int top = 0;
    if (!sweep_is_regime(rlo) || !sweep_is_regime(rhi) || !strcmp(rlo->regime, rhi->regime)) return;
    if (sweep_table_find_boundary(t->known, t->phi, t->dl, rlo->gamma, rhi->gamma)) return;
    stack[top].lo = rlo->gamma;
    stack[top].hi = rhi->gamma;
    snprintf(stack[top].rlo, sizeof stack[top].rlo, "%s", rlo->regime);
    snprintf(stack[top].rhi, sizeof stack[top].rhi, "%s", rhi->regime);
    top++;
    while (top > 0 && !*t->cancel) {
        struct part p = stack[--top];
        char note[160] = "";
        for (int it = 0; p.hi - p.lo > t->sp->gamma_tol && it < 60 && !*t->cancel; it++) {
            double mid = 0.5 * (p.lo + p.hi);
            sweep_row rm;
            probe(t, from, mid, &rm);
            if (!strcmp(rm.regime, p.rlo)) {
                p.lo = mid;
            } else if (!strcmp(rm.regime, p.rhi)) {
                p.hi = mid;
            } else if (sweep_is_regime(&rm) && top < 8) {
                stack[top].lo = mid;
                stack[top].hi = p.hi;
                snprintf(stack[top].rlo, sizeof stack[top].rlo, "%s", rm.regime);
                snprintf(stack[top].rhi, sizeof stack[top].rhi, "%s", p.rhi);
                top++;
                p.hi = mid;
                snprintf(p.rhi, sizeof p.rhi, "%s", rm.regime);
            } else {
                snprintf(note, sizeof note, "bisection stopped: Gamma %.6g is %s", mid, rm.regime);
                break;
            }
        }
        if (*t->cancel) break;
        sweep_row b;
        row_init(t, &b, 'b', 0.5 * (p.lo + p.hi));
        b.gamma_lo = p.lo;
        b.gamma_hi = p.hi;
        snprintf(b.regime, sizeof b.regime, "boundary");
        snprintf(b.first_type, sizeof b.first_type, "none");
        if (!note[0]) snprintf(note, sizeof note, "%s below; %s above", p.rlo, p.rhi);
        snprintf(b.note, sizeof b.note, "%s", note);
        emit(t, &b, 1);
    }
}

void sweep_run_row(const sweep_spec *sp, double phi, double dl, const sweep_table *known, sweep_emit_fn emit_fn,
                   void *ctx, const volatile sig_atomic_t *cancel)
{
    static const volatile sig_atomic_t never = 0;
    row_task t;
    memset(&t, 0, sizeof t);
    t.sp = sp;
    t.phi = phi;
    t.dl = dl;
    t.known = known;
    t.emit = emit_fn;
    t.ctx = ctx;
    t.cancel = cancel ? cancel : &never;
    int ng = sp->ngamma;
    upper *ups = calloc((size_t)ng, sizeof *ups);
    sweep_row *rows = calloc((size_t)ng, sizeof *rows);
    rod *probe_rod = NULL;
    /* The solver is sized on the first grid point the mesh can hold (every Gamma gives the same
     * node count); a point it cannot hold fails alone, with rod_scene_check's reason (issue 33,
     * item 10: one such point made every point of the row "out of memory"). */
    char bad[160] = "";
    int first_ok = -1;
    for (int j = 0; j < ng && first_ok < 0; j++) {
        rod_scene sc = scene_at(&t, sp->gamma[j]);
        if (rod_scene_check(&sc, NULL, 0, NULL, 0) == 0) first_ok = j;
    }
    if (first_ok >= 0) {
        rod_scene sc = scene_at(&t, sp->gamma[first_ok]);
        if (rod_alloc(&sc, &probe_rod, bad, sizeof bad) == ROD_OK) t.s = rod_solver_alloc(probe_rod);
    }
    if (!ups || !rows || !t.s) {
        /* Every point failed, with the reason (never a half-written row). */
        for (int j = 0; j < ng; j++) {
            sweep_row r;
            rod_scene sc = scene_at(&t, sp->gamma[j]);
            char msg[160] = "";
            row_init(&t, &r, 'p', sp->gamma[j]);
            snprintf(r.regime, sizeof r.regime, "failed");
            snprintf(r.first_type, sizeof r.first_type, "none");
            if (rod_scene_check(&sc, msg, sizeof msg, NULL, 0) != 0) snprintf(r.note, sizeof r.note, "%s", msg);
            else snprintf(r.note, sizeof r.note, "%s", bad[0] ? bad : "out of memory allocating the row task");
            emit_fn(ctx, &r, 1);
        }
        goto done;
    }
    /* Steps 1 and 2, unless every point is known already (their states are needed only to seed
     * the probes, which a complete row does not run). */
    int all_known = 1;
    for (int j = 0; j < ng; j++) all_known = all_known && known_row(&t, sp->gamma[j]) != NULL;
    int need_states = !all_known;
    for (int j = 0; j + 1 < ng && !need_states; j++) {
        const sweep_row *a = known_row(&t, sp->gamma[j]), *b = known_row(&t, sp->gamma[j + 1]);
        need_states = sweep_is_regime(a) && sweep_is_regime(b) && strcmp(a->regime, b->regime) &&
                      !sweep_table_find_boundary(known, phi, dl, sp->gamma[j], sp->gamma[j + 1]);
    }
    if (need_states) chain(&t, ups);
    for (int j = 0; j < ng && !*t.cancel; j++) {
        const sweep_row *k = known_row(&t, sp->gamma[j]);
        if (k) {
            rows[j] = *k;
            emit(&t, &rows[j], 0);
            continue;
        }
        row_init(&t, &rows[j], 'p', sp->gamma[j]);
        classify(&ups[j], &rows[j]);
        emit(&t, &rows[j], 1);
    }
    for (int j = 0; j + 1 < ng && !*t.cancel; j++)
        bisect_cell(&t, ups[j].r ? &ups[j] : &ups[j + 1], &rows[j], &rows[j + 1]);
done:
    for (int j = 0; ups && j < ng; j++) upper_free(&ups[j]);
    free(ups);
    free(rows);
    rod_solver_free(t.s);
    rod_free(probe_rod);
    sweep_table_free(&t.mine);
}

int sweep_row_complete(const sweep_spec *sp, double phi, double dl, const sweep_table *t)
{
    for (int j = 0; j < sp->ngamma; j++)
        if (!sweep_table_find(t, phi, sp->gamma[j], dl)) return 0;
    for (int j = 0; j + 1 < sp->ngamma; j++) {
        const sweep_row *a = sweep_table_find(t, phi, sp->gamma[j], dl);
        const sweep_row *b = sweep_table_find(t, phi, sp->gamma[j + 1], dl);
        if (sweep_is_regime(a) && sweep_is_regime(b) && strcmp(a->regime, b->regime) &&
            !sweep_table_find_boundary(t, phi, dl, sp->gamma[j], sp->gamma[j + 1]))
            return 0;
    }
    return 1;
}
