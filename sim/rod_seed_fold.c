/* rod_seed_fold.c: the fold ending a followed state, located by the fold system of rod_critical.c
 * with Gamma or phi free and Delta W held (see rod_seed_fold.h). */
#include "rod_seed_fold.h"
#include "rod_observe.h"
#include "rod_route.h"
#include "rod_seed.h"
#include "rod_solver.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double dz_of(const rod *r)
{
    double *k1 = malloc(sizeof(double) * (size_t)r->n);
    rod_obs ob = {0};
    int ok = k1 != NULL;
    if (ok) rod_observe(r, k1, &ob);
    free(k1);
    return ok && isfinite(ob.dz) ? ob.dz : 0.0;
}

rod_status rod_seed_fold_locate(const rod *last, const rod_scene *last_sc, const rod_scene *to_sc,
                                rod_seed_fold_report *rep)
{
    memset(rep, 0, sizeof *rep);
    int dg = to_sc->fold_position != last_sc->fold_position, dp = to_sc->fold_angle_deg != last_sc->fold_angle_deg;
    if (dg == dp || last_sc->fold_angle_deg == 0.0 || last->n != last_sc->nodes) {
        snprintf(rep->why, sizeof rep->why, "fold not located: the path must change Gamma or the crease angle, not both "
                 "nor neither, on a creased scene");
        return ROD_ERR_SCENE;
    }
    rep->par = dg ? ROD_PAR_GAMMA : ROD_PAR_PHI;
    /* The parameter in its reported unit: Gamma, or |phi| in degrees. */
    double from = dg ? last_sc->fold_position : fabs(last_sc->fold_angle_deg);
    double target = dg ? to_sc->fold_position : fabs(to_sc->fold_angle_deg);
    rep->from = rep->at = from;
    rod *r = NULL;
    rod_status st = rod_alloc(last_sc, &r, rep->why, sizeof rep->why);
    if (st != ROD_OK) return st;
    if ((st = rod_seed_remap(last, r, last_sc->compression)) != ROD_OK) {
        snprintf(rep->why, sizeof rep->why, "fold not located: the last state's mesh differs from its scene's");
        rod_free(r);
        return st;
    }
    rep->dz_from = rep->dz = dz_of(r);
    rod_crit_opts co = rod_crit_opts_default();
    co.tolerance = last_sc->tolerance;
    rod_crit *c = rod_crit_alloc(r, &co);
    if (!c) {
        rod_free(r);
        snprintf(rep->why, sizeof rep->why, "out of memory");
        return ROD_ERR_ALLOC;
    }
    rod_crit_set_phase1_cap(c, 20);
    double to_units = r->length * r->length / r->EI1[0];
    double dir = target > from ? 1.0 : -1.0, span = fabs(target - from);
    const char *name = dg ? "Gamma" : "phi";
    char first_why[120] = "";
    /* Both kinds, the block whose mode is nearest zero at the last state first: even, a fold (the
     * state vanishes); odd, a pitchfork (the symmetric state goes on, unstable). Near a sharp fold
     * the odd mode can still be the nearer one a few 1e-6 before it (measured at phi 135 deg,
     * Gamma 0.239), so the other kind is tried when the first is not the end. */
    int order[2] = {0, 1};
    for (int attempt = 0; attempt < 2 && !rep->located; attempt++) {
        double p[ROD_NPAR];
        p[ROD_PAR_DW] = 0.0;
        p[ROD_PAR_GAMMA] = last_sc->fold_position;
        p[ROD_PAR_PHI] = last_sc->fold_angle_deg * M_PI / 180.0;
        p[ROD_PAR_DL] = last_sc->compression;
        rod_crit_report cr;
        char why[200] = "";
        if (attempt > 0) {
            /* Afresh: the failed solve moved the state and maybe the mesh (Gamma). */
            snprintf(first_why, sizeof first_why, "%.119s", rep->why);
            rod_crit_free(c);
            rod_free(r);
            r = NULL;
            c = NULL;
            if (rod_alloc(last_sc, &r, NULL, 0) != ROD_OK || rod_seed_remap(last, r, last_sc->compression) != ROD_OK ||
                !(c = rod_crit_alloc(r, &co))) {
                snprintf(rep->why, sizeof rep->why, "out of memory");
                st = ROD_ERR_ALLOC;
                break;
            }
            rod_crit_set_phase1_cap(c, 20);
        }
        st = rod_crit_modes(c, p, &cr, why, sizeof why);
        if (st != ROD_OK) {
            snprintf(rep->why, sizeof rep->why, "fold not located: %.200s", why);
            break;
        }
        if (attempt == 0 && fabs(cr.eig_odd) < fabs(cr.eig_even)) {
            order[0] = 1;
            order[1] = 0;
        }
        int pf = rep->pitchfork = order[attempt];
        rep->eig_from = (pf ? cr.eig_odd : cr.eig_even) * to_units;
        const rod_par freep[1] = {rep->par};
        rod_status ss = rod_crit_solve(c, pf ? ROD_CRIT_PITCHFORK : ROD_CRIT_FOLD, freep, p, &cr, why, sizeof why);
        rep->iterations += cr.iterations;
        if (ss != ROD_OK) {
            snprintf(rep->why, sizeof rep->why, "%s not located: Newton on its system in %s did not converge: %.150s",
                     pf ? "pitchfork" : "fold", name, why);
            continue;
        }
        rep->at = dg ? p[ROD_PAR_GAMMA] : fabs(p[ROD_PAR_PHI]) * 180.0 / M_PI;
        rep->dz = dz_of(r);
        double eig = pf ? cr.eig_odd : cr.eig_even, par = pf ? cr.parity_odd : cr.parity_even;
        rep->eig = eig * to_units;
        rep->eig_rel = cr.scale > 0.0 ? fabs(eig) / cr.scale : 0.0;
        rep->parity = par;
        rep->residual_rel = cr.residual_rel;
        rep->n_negative = cr.n_negative;
        if (!(pf ? par < -0.5 : par > 0.5))
            snprintf(rep->why, sizeof rep->why, "not the end: the critical mode at %s %.6g has parity %.2f, not %s", name,
                     rep->at, par, pf ? "odd" : "even");
        else if (cr.n_negative != 0)
            snprintf(rep->why, sizeof rep->why, "not the end: %d other eigenvalues are negative at the %s (%s %.6g)",
                     cr.n_negative, pf ? "pitchfork" : "fold", name, rep->at);
        else if ((rep->at - from) * dir < -1e-3 * span || (target - rep->at) * dir <= 0.0)
            snprintf(rep->why, sizeof rep->why, "not the end: the %s at %s %.6g is not between the last state (%.6g) "
                     "and the target (%.6g)", pf ? "pitchfork" : "fold", name, rep->at, from, target);
        else if (!(fabs(rep->dz - rep->dz_from) <= 0.05))
            snprintf(rep->why, sizeof rep->why, "not the end: the %s's Delta Z %.4f is far from the last state's %.4f "
                     "(another branch)", pf ? "pitchfork" : "fold", rep->dz, rep->dz_from);
        else
            rep->located = 1;
    }
    if (!rep->located && first_why[0]) {
        size_t k = strlen(rep->why);
        snprintf(rep->why + k, sizeof rep->why - k, "; first: %.100s", first_why);
    }
    rod_crit_free(c);
    rod_free(r);
    return st == ROD_OK || rep->located ? ROD_OK : st;
}

int rod_seed_end_between(const rod_scene *from_sc, const rod_scene *to_sc, rod_seed_fold_report *rep)
{
    memset(rep, 0, sizeof *rep);
    rod_scene a = *from_sc, b = *to_sc;
    a.fold_angle_rel = b.fold_angle_rel = 0.0;
    rod *r = NULL, *out = NULL, *last = NULL;
    if (rod_alloc(&a, &r, rep->why, sizeof rep->why) != ROD_OK) return 0;
    rod_solver *s = rod_solver_alloc(r);
    if (!s) {
        rod_free(r);
        return -1;
    }
    int found = 0;
    rod_route_report rr = {0};
    rod_seed_report sr;
    rod_scene lsc;
    if (rod_route_to_state(r, s, &a, +1, &rr) != ROD_OK || rod_seed_is_stable(r) != 1) {
        snprintf(rep->why, sizeof rep->why, "no stable upper state at the start");
    } else if (rod_seed_continue_keep(r, &a, &b, s, &out, &sr, &last, &lsc) == ROD_OK) {
        snprintf(rep->why, sizeof rep->why, "continuation reached the target: its upper state exists");
    } else if (!last) {
        snprintf(rep->why, sizeof rep->why, "continuation did not take a step");
    } else {
        rod_status st = rod_seed_fold_locate(last, &lsc, &b, rep);
        found = st == ROD_ERR_ALLOC ? -1 : rep->located;
    }
    rod_free(out);
    rod_free(last);
    rod_solver_free(s);
    rod_free(r);
    return found;
}
