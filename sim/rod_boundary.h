/* rod_boundary.h: the regime boundary traced directly: the codimension-2 point Gamma*(phi, Delta L)
 * where the upper symmetric branch's pitchfork and saddle-node coincide, found from a scene and
 * continued in phi and Delta L; and the fold and pitchfork curves in (Gamma, Delta W) through it.
 *
 * Start (rod_boundary_start). The perfect scene (imperfection off, as rod_bifurcation.h): route
 * to the upper state, primary branch in Delta W by continuation (rod_continue.h) up to two
 * negative eigenvalues. Its saddle-node is polished as a point of the fold curve (rod_critical.h,
 * free Delta W), then followed in Gamma: first a scan in steps of 0.005 (toward larger Gamma when
 * the pitchfork came first, smaller when the saddle-node did, then the other way) until the odd
 * block's test function g_odd changes sign, then secant steps on g_odd to a step below 1e-7.
 * (The fold curve rather than the pitchfork curve: g_odd is monotone on it, while g_even along the
 * pitchfork curve is not near Gamma 0.13, measured.) With the pitchfork first, the odd bordering
 * vector at the fold is the pitchfork's mode continued, found by shift-invert iteration below the
 * odd block's negative eigenvalue. The search stops, naming why, when Gamma leaves
 * [gamma_min, gamma_max], when g_odd moves away from zero three times (the two bifurcations do
 * not meet), or at its step cap. The codim-2 point is the fold-curve point with g_odd = 0: the
 * Hessian's even and odd blocks both singular.
 *
 * Continuation (rod_boundary_move). Natural-parameter continuation of the codimension-2 point in
 * phi or Delta L with a quadratic predictor from the last three points (Gamma, Delta W and q); each
 * point is located as at the start (fold curve, secant on g_odd from the predicted Gamma, with the
 * last slope); steps halved on failure down to a minimum and grown by 1.5 after an easy solve. Each accepted point
 * has a verified pair of critical modes (even and odd). Stops, with every good point kept: Gamma
 * outside [gamma_min, gamma_max], phi reaching 0 or 180 deg, a step below the minimum.
 *
 * Mesh. By default the outer edge count of the start's mesh is held (rod_mesh_set), so every
 * rest quantity and Gamma*(phi) is smooth; `continue` and `sweep` build each Gamma's own mesh
 * (rod_mesh_outer_edges), which differs from it by whole edges: at N = 61 the traced Gamma* is
 * 0.17507 with 12 outer edges and 0.17583 with 8 (the sweep's mesh there has 10). match_mesh = 1
 * re-meshes each point to rod_alloc's mesh (interpolation, a static solve below the fold, the
 * search again); it does not converge reliably yet (the interpolated state is strained), so it is
 * off by default.
 *
 * Regime boundary. The codim-2 point decides the regime only while the upper branch is stable up
 * to it: every other eigenvalue positive there (n_negative 0). Where another mode went unstable
 * earlier on the branch (at phi 45 deg, N = 61, Gamma 0.13, another pitchfork at Delta W 0.32 comes
 * before this codim-2 point at 0.54 and the branch restabilises in between, measured), the point
 * is still a codim-2 point but no longer the boundary. The inertia at the point cannot see that
 * (n_negative 0 there), so rod_boundary_move checks by the sweep's own classification
 * (rod_bifurcation_analyse, rod_analysis_opts_classify) just below Gamma*, every verify_every:
 * the first instability must lie within 0.02 of the point's Delta W. Where it does not, the move
 * stops with a reason, the points before kept.
 *
 * Direct or located. Each continued point can be solved directly, by Newton on the whole
 * codim-2 system (R = 0, g_even = 0, g_odd = 0 in q, Delta W and Gamma; rod_critical.h, with the
 * even block's near-singular direction deflated), from the predictor, falling back to the
 * location along the fold curve when it fails (opts.direct). Measured (bench's 100 deg of phi,
 * docs/boundary.md): at N = 61 the two agree to 8e-7 in Gamma* and cost the same; at N = 201 the
 * direct solve converged in 79 of 257 tries (mean 6.8 iterations, each about 8 Hessian
 * assemblies), its Gamma* scattered by up to 1.2e-4 around the located one (the test functions'
 * round-off floor, 1e-16 max |K_ii| = 4e-6, against derivatives near 1), and the trace took
 * about 1 s more CPU. So it is off by default.
 *
 * No result field is NaN; every stop has a reason. */
#ifndef RIBBON_SIM_ROD_BOUNDARY_H
#define RIBBON_SIM_ROD_BOUNDARY_H

#include <stddef.h>

#include "rod_continue.h"
#include "rod_critical.h"
#include "scene.h"

typedef struct rod_boundary_opts {
    rod_crit_opts crit;
    rod_cont_opts cont;        /* the primary branch of the start (tolerance from the scene) */
    double gamma_min, gamma_max; /* the boundary must stay in this range */
    double gamma_step;         /* largest Gamma step of the start's search */
    int max_search;            /* cap on the search's steps */
    double phi_step_deg;       /* initial and largest step in phi, deg */
    double dl_step;            /* initial and largest step in Delta L */
    double min_step_frac;      /* a step below this fraction of the initial one stops */
    int max_steps;             /* cap on steps of one continuation */
    int match_mesh;            /* 1: re-mesh each point as rod_alloc would (see above) */
    double verify_every;       /* check that the point is the regime boundary (see above) at
                                  least every this far in phi (deg) or Delta L / 100; 0: never */
    int direct;                /* 1: each continued point by Newton on the codim-2 system first
                                  (free Delta W and Gamma, rod_crit_solve ROD_CRIT_CODIM2, from the
                                  predictor, capped at 10 iterations), the location along
                                  the fold curve only when it fails; 0 (default): the location
                                  only (see "Direct or located" above) */
    int phase1_cap;            /* a continued point's solves fail after this many iterations still
                                  far from equilibrium (rod_crit_set_phase1_cap); the step halves */
    int verify_ends;           /* 1: also check at the end of every move (0: only every
                                  verify_every along consecutive moves; rod_boundary_check) */
    int predictor;             /* a continued point's first guess (q, Gamma, Delta W): 2 (default)
                                  quadratic through the last three points of the continuation,
                                  1 secant through the last two (the first step after a start or a
                                  re-mesh uses what it has) */
} rod_boundary_opts;

/* Gamma in [0.02, 0.45], gamma_step 0.02, 40 search steps, phi steps of 5 deg, Delta L steps of
 * 0.05, minimum 1/64 of them, 400 steps, match_mesh 0, verify_every 10, direct 0, verify_ends 1,
 * phase1_cap 20, predictor 2. */
rod_boundary_opts rod_boundary_opts_default(void);

typedef struct rod_codim2_point {
    double phi_deg;        /* crease angle magnitude, deg */
    double dl;             /* Delta L */
    double gamma;          /* Gamma* */
    double dw;             /* Delta W where pitchfork and saddle-node coincide */
    double dz;             /* Delta Z there */
    double eig_even, eig_odd;       /* the two critical eigenvalues (Rayleigh quotients) */
    double eig_scale;      /* max |K_ii| (the eigenvalues' round-off floor is ~1e-16 of it) */
    double parity_even, parity_odd; /* C2 parities of their modes (+1, -1) */
    double residual_rel;   /* equilibrium residual over EI1 / l^2 */
    int outer_edges;       /* mesh edges between clamp and crease */
    int n_negative;        /* other eigenvalues already negative there: 0 on the regime boundary;
                              > 0 means an earlier instability decides the snap (see move) */
    int iterations;        /* Newton iterations of its solve */
    int direct;            /* 1: solved by the direct codim-2 Newton, 0: located along the fold curve */
} rod_codim2_point;

typedef struct rod_boundary_curve {
    rod_codim2_point *pts; /* in order of the swept parameter */
    size_t n, cap;
    rod_status end_status; /* ROD_OK when the range was covered */
    char end_reason[256];  /* why it ended (always set) */
} rod_boundary_curve;

void rod_boundary_curve_free(rod_boundary_curve *c);

/* A point of the fold or pitchfork curve in (Gamma, Delta W). */
typedef struct rod_crit_curve_point {
    double gamma, dw, dz;
    double g_other;        /* the other block's test function (changes sign at Gamma*) */
} rod_crit_curve_point;

typedef struct rod_crit_curve {
    rod_crit_curve_point *pts; /* ascending Gamma */
    size_t n, cap;
    rod_status end_status;
    char end_reason[256];
} rod_crit_curve;

void rod_crit_curve_free(rod_crit_curve *c);

typedef struct rod_boundary rod_boundary;

/* Finds the codimension-2 point of the scene (its phi, Gamma as the start, Delta L) into *out.
 * On failure *b is still returned when the start got far enough to have a state (NULL
 * otherwise) and why says what stopped; the scene's imperfection is ignored. */
rod_status rod_boundary_start(const rod_scene *sc, const rod_boundary_opts *o, rod_boundary **b,
                              rod_codim2_point *out, char *why, size_t why_len);
void rod_boundary_free(rod_boundary *b);

/* Continues the current codimension-2 point in phi (par ROD_PAR_PHI, target in degrees of
 * magnitude) or Delta L (ROD_PAR_DL) to target. Accepted points (not the start) are appended to
 * rec unless NULL. On a stop the current point is the last good one. rec's end fields are set. */
rod_status rod_boundary_move(rod_boundary *b, rod_par par, double target, rod_boundary_curve *rec);

/* Keeps the current codimension-2 point (state included) as the mark / makes the mark current
 * again: a caller that traces several ranges from one point returns there between them. */
void rod_boundary_mark(rod_boundary *b);
void rod_boundary_return(rod_boundary *b);

/* The regime-boundary check of rod_boundary_move at the current point: 1 when the first
 * instability just below Gamma* lies within 0.02 of its Delta W (or the check cannot tell), 0
 * when an earlier instability decides; *first_dw gets that instability's Delta W (0: none). */
int rod_boundary_check(const rod_boundary *b, double *first_dw);

/* The current codimension-2 point. */
void rod_boundary_current(const rod_boundary *b, rod_codim2_point *out);

/* The fold (ROD_CRIT_FOLD) or pitchfork curve at the current phi and Delta L through the current
 * codimension-2 point, at the Gammas gamma_lo + k dgamma inside [gamma_lo, gamma_hi] (one more
 * point at Gamma* itself). The current point is not moved. */
rod_status rod_boundary_crit_curve(rod_boundary *b, rod_crit_kind kind, double gamma_lo, double gamma_hi,
                                   double dgamma, rod_crit_curve *out);

/* Counters of the simulator work so far. */
rod_counters rod_boundary_counters(const rod_boundary *b);

#endif
