/* rod_bifurcation.h: bifurcation analysis of a scene, what `ribbon-sim continue` prints: the
 * upper state at Delta L (the documented route), the primary branch in Delta W by continuation
 * (rod_continue.h), its located and classified events, the asymmetric branch switched onto at
 * the first pitchfork, and the predicted regime.
 *
 * Perfect scene. Bifurcations are properties of the symmetric model: with the imperfection on,
 * a pitchfork unfolds into a fold of the load path a little earlier (by about rel^(2/3)) plus a
 * disconnected branch. By default the analysis therefore traces the scene with
 * imperfection.fold_angle_rel = 0, whose discrete model is exactly C2-symmetric (rod.c), so the
 * primary branch stays symmetric and the pitchfork is a clean change of the negative count with
 * an antisymmetric mode. keep_imperfection = 1 traces the scene as given: the primary branch
 * then turns at a limit point in Delta W a little before the perfect pitchfork (subcritical
 * case) and goes on as the asymmetric branch. That limit point is the imperfect pitchfork: it is
 * located like any fold and reported as a pitchfork (critical mode nearly antisymmetric) with
 * fold = 1, and no branch is switched onto there (the primary branch already is the asymmetric
 * one). Its tracer steps that jump across the sharp turn onto the disconnected branch nearby are
 * refused (rod_continue.c: the event's bracket does not close) and redone shorter.
 *
 * Regime: the first instability met on the primary branch starting from the stable upper state
 * (the first event where the negative count leaves 0) decides: pitchfork first is an asymmetric
 * snap, saddle-node first a symmetric one. */
#ifndef RIBBON_SIM_ROD_BIFURCATION_H
#define RIBBON_SIM_ROD_BIFURCATION_H

#include "rod.h"
#include "rod_continue.h"
#include "scene.h"

#define ROD_ANALYSIS_MAX_BRANCHES 4

typedef struct rod_analysis_opts {
    rod_cont_opts cont;     /* continuation options (tolerance taken from the scene) */
    int keep_imperfection;  /* 0 (default): analyse the perfect scene, see above */
    int switch_branches;    /* 1 (default): trace the branch leaving the first pitchfork */
    double switch_offset;   /* scaled displacement along the critical mode, default 0.01 */
} rod_analysis_opts;

rod_analysis_opts rod_analysis_opts_default(void);

/* Classification only (what a sweep point needs): the primary branch ends just past its first
 * instability (max_negative 0), no branch switching. */
rod_analysis_opts rod_analysis_opts_classify(void);

typedef struct rod_analysis {
    rod_branch branches[ROD_ANALYSIS_MAX_BRANCHES]; /* 0: primary; then switched branches */
    int nbranches;
    rod_event events[ROD_CONT_MAX_EVENTS];
    int nevents;
    int first;              /* index in events of the first instability of the primary branch, -1 */
    const char *regime;     /* "asymmetric", "symmetric" or "none" (static string) */
    double dz_upper;        /* Delta Z of the upper state at Delta W = 0 */
    double fold_angle_rel;  /* imperfection actually used */
    double worst_residual;  /* largest accepted corrector residual over EI1 / l^2 beyond the
                               tolerance (rod_tracer_worst_residual), 0 when none */
    double route_wall_s;    /* s, wall time of the route to the upper state */
    double wall_s;          /* s, wall time of the whole analysis */
    rod_counters count;
} rod_analysis;

/* Runs the analysis. Fails (with err) when the scene is invalid or the upper state cannot be
 * reached; a branch that ends early is not a failure (its end_status and end_reason say why). */
rod_status rod_bifurcation_analyse(const rod_scene *sc, const rod_analysis_opts *o, rod_analysis *out, char *why,
                                   size_t why_len);
/* The same from a given upper state instead of the route: start is an equilibrium of this
 * scene's rod (the perfect one unless keep_imperfection; the same mesh), e.g. one reached by
 * continuation from a neighbouring scene (rod_seed.h). It is re-solved to the scene's tolerance
 * first; route_wall_s is then that solve's time. start NULL: the route, as above. */
rod_status rod_bifurcation_analyse_from(const rod_scene *sc, const rod_analysis_opts *o, const rod *start,
                                        rod_analysis *out, char *why, size_t why_len);
void rod_analysis_free(rod_analysis *a);

#endif
