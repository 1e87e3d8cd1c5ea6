/* rod_seed.h: a stable state at a new crease (phi, Gamma) from a solved neighbour's, by
 * continuation in the crease angle and position at fixed Delta L, Delta W = 0, instead of a
 * fresh route from the flat ribbon (rod_route.h). What a sweep uses to reach the upper state at
 * each grid point from the point next to it (issue 16, part B).
 *
 * The mesh (rod.c) puts nodes on both creases, so the nodes move with Gamma: node positions over
 * the three segments [0, Gamma], [Gamma, 1 - Gamma], [1 - Gamma, 1] are carried over by their
 * position relative to their segment (rod_seed_remap), which keeps the kink at the crease node
 * even when the node count of a segment changes (every 1 / (N - 3) in Gamma). The path
 * (phi, Gamma)(p), p in [0, 1], is a straight line; each step remaps the last converged state to
 * the mesh at p and solves it with Newton for a stable state (LDL^T, the route's solver
 * settings); a failed step is halved, a quick one grows. Stop: when the step would go below
 * 2^-10 of the nominal one, the path has met a fold of the followed state (or Newton cannot
 * follow it): the status is ROD_ERR_BRANCH_LOST and the report keeps where the state was last
 * solved and its lowest Hessian eigenvalue there against the start's, the evidence that it
 * vanishes (at a fold that eigenvalue goes to zero). A step whose solution jumps in Delta Z
 * (Newton slid onto another state) or is not stable (a negative eigenvalue: the state lost its
 * stability within the step, where an eigenvalue crosses zero) counts as failed, so the path
 * ends at the last stable state before a fold or a loss of stability. */
#ifndef RIBBON_SIM_ROD_SEED_H
#define RIBBON_SIM_ROD_SEED_H

#include "rod.h"
#include "rod_solver.h"
#include "scene.h"

typedef struct rod_seed_report {
    int solves;             /* Newton solves run */
    int newton_iterations;  /* their iterations */
    double reached;         /* fraction of the path solved (1 on success) */
    double phi_reached;     /* deg (signed, as the scene's), Gamma of the last solved state */
    double gamma_reached;
    double eig_start;       /* lowest Hessian eigenvalue at the start, over E I1 / l^2 ... */
    double eig_last;        /* ... and at the last solved state (set on a failure, else 0) */
    rod_status last_failure; /* status of the last failed solve (ROD_OK if none) */
} rod_seed_report;

/* Copies the state of src onto dst, two rods of the same node count and length (Gamma may
 * differ): positions and twist angles by position within their segment, frames from the
 * corresponding edge, then dst's clamps at (dl, 0) and frames updated. ROD_ERR_SCENE when
 * the node counts differ. */
rod_status rod_seed_remap(const rod *src, rod *dst, double dl);

/* 1 when the Hessian at r's state has no negative eigenvalue (its inertia, one banded LDL^T),
 * 0 when it has, -1 when it cannot be told (out of memory, factorisation failed). */
int rod_seed_is_stable(rod *r);

/* From the equilibrium in `from` (a rod of scene from_sc) to a new rod in equilibrium at to_sc
 * (*out, the caller frees it with rod_free). from_sc and to_sc may differ only in the crease
 * angle and position (ROD_ERR_SCENE otherwise). s is a solver of the same node count. On a
 * failure *out is NULL and rep says where and why the path stopped. */
rod_status rod_seed_continue(const rod *from, const rod_scene *from_sc, const rod_scene *to_sc, rod_solver *s,
                             rod **out, rod_seed_report *rep);

/* As rod_seed_continue; on a failure *last (unless last is NULL) gets the last stable state the
 * path solved (a rod of scene *last_sc, at rep->phi_reached, rep->gamma_reached; the caller frees
 * it), or NULL when no step was solved: where to look for the fold that ended the path
 * (rod_seed_fold.h). */
rod_status rod_seed_continue_keep(const rod *from, const rod_scene *from_sc, const rod_scene *to_sc, rod_solver *s,
                                  rod **out, rod_seed_report *rep, rod **last, rod_scene *last_sc);

#endif
