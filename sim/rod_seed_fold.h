/* rod_seed_fold.h: where a stable state followed in the crease position or angle ends (issue 16,
 * part B): the fold of the symmetric state at fixed Delta W (the clamps' shear) in the
 * continuation's own parameter, Gamma or phi, located directly.
 *
 * rod_seed_continue (rod_seed.h) follows a state at Delta W = 0 from a solved neighbour and stops
 * where its step would fall below 2^-10 of the nominal one. That is evidence, not a location: the
 * lowest eigenvalue at the last state can still be 0.2-0.5 E I1 / l^2 a few hundredths of a
 * degree before a sharp fold (it goes to zero as the square root of the distance). This locates
 * the fold from that last state: Newton on the minimally augmented fold system of rod_critical.h
 * (R = 0 and the even block's test function g_even = 0), unknowns the even part of q and the
 * path's parameter (Gamma or phi), Delta W and Delta L held. The even bordering vector starts as
 * the even block's mode nearest zero at the last state. Capped: rod_crit's 40 Newton iterations,
 * of which at most 20 far from equilibrium.
 *
 * Why Delta W can be held. The shear's load vector is odd under the mirror y -> -y (the width
 * direction), the states at Delta W = 0 and their critical mode even: where the upper state ends
 * at Delta W = 0, its saddle-node in Delta W has come down to Delta W = 0 as the square root of
 * the distance (measured at phi 133.75-133.825 deg, Gamma 0.244: Delta W_fold^2 linear in phi,
 * docs/upper-state-fold-phi135.md), so at Delta W = 0 it is a fold in phi (or Gamma) itself, a
 * regular solution of this system.
 *
 * Accepted as the end of the followed state (located = 1) only when: Newton converged; the mode
 * is even (parity > 0.5); no other eigenvalue is negative there (n_negative 0: the end of the
 * stable state, not a fold of an already unstable one); the fold lies on the path, ahead of the
 * last state (by at most 1e-3 of the span behind it, round-off) and before the target; and its
 * Delta Z is within 0.05 of the last state's (the same state, not another branch). */
#ifndef RIBBON_SIM_ROD_SEED_FOLD_H
#define RIBBON_SIM_ROD_SEED_FOLD_H

#include <stddef.h>

#include "rod.h"
#include "rod_critical.h"
#include "scene.h"

typedef struct rod_seed_fold_report {
    int located;         /* 1: the followed state ends at this fold (conditions above) */
    rod_par par;         /* ROD_PAR_GAMMA or ROD_PAR_PHI */
    int pitchfork;       /* 0: a fold (even mode; the state ends); 1: a pitchfork (odd mode; the
                            symmetric state goes on past it, unstable) */
    double from, at;     /* the parameter (Gamma, or |phi| in deg) at the last state and at the fold */
    double dz_from, dz;  /* Delta Z at both */
    double eig_from;     /* the even block's eigenvalue nearest zero at the last state, over E I1 / l^2 */
    double eig;          /* ... at the fold (its round-off floor is ~1e-16 of max |K_ii|) */
    double eig_rel;      /* |eig| / max |K_ii| */
    double parity;       /* C2 parity of the critical mode (+1 even) */
    double residual_rel; /* equilibrium residual over E I1 / l^2 */
    int n_negative;      /* other negative eigenvalues at the fold */
    int iterations;      /* Newton iterations */
    char why[240];       /* located = 0: why (also when Newton converged elsewhere) */
} rod_seed_fold_report;

/* Locates the fold ending the path from the state `last` (a rod of scene last_sc in equilibrium at
 * Delta W = 0) toward to_sc, which may differ from last_sc in Gamma or in the crease angle, not
 * both (ROD_ERR_SCENE, named in rep->why). `last` is not changed. Returns ROD_OK when the
 * computation ran (rep->located says whether it found the end), an error when it could not
 * (out of memory, no critical mode). */
rod_status rod_seed_fold_locate(const rod *last, const rod_scene *last_sc, const rod_scene *to_sc,
                                rod_seed_fold_report *rep);

/* The same from scratch, for callers without a neighbour's state (the predicted phase map): the
 * route to the upper state of from_sc (perfect scene), continuation toward to_sc (differing in
 * Gamma or the crease angle), and the location where it stops. 1 when the state ends before
 * to_sc at a located fold or pitchfork (rep says where), 0 when it does not (to_sc reached, the
 * route failed, or nothing located: rep->why), -1 out of memory. */
int rod_seed_end_between(const rod_scene *from_sc, const rod_scene *to_sc, rod_seed_fold_report *rep);

#endif
