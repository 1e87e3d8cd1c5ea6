/* rod_continue.h: pseudo-arclength continuation of rod equilibria along a clamp load path
 * (rod_load.h), with stability at every point and located, classified critical points.
 *
 * Unknowns and scaling. X = (q_free, lambda). Arclength is measured in the scaled coordinates
 *     Y = (q_k / (u_k sqrt(n_free)), lambda / lambda_scale),  u_k = l for positions, 1 rad for angles,
 * so a step ds moves the free DOFs by about ds l (RMS) or the load by ds lambda_scale.
 *
 * Step (Keller's pseudo-arclength, which passes folds in lambda):
 *   tangent   K b = f (K the free Hessian, f = dR/dlambda), tau ~ (-b, 1) in Y, unit length,
 *             oriented along the previous tangent (the first one along +-lambda);
 *   predictor Y_p = Y_k + ds tau_k + (ds^2 / 2) kappa_k, kappa_k = (tau_k - tau_{k-1}) / ds_{k-1}
 *             the path's curvature from the last two tangents (0 at a branch start). Most of the
 *             predictor's residual is the stiff stretching of edges that a straight step
 *             rotates, a second-order effect that kappa removes for the most part: the first
 *             residual drops about fourfold and half as many steps reach the same point;
 *   corrector Newton on R(X) = 0 and tau_k . (Y - Y_p) = 0, by bordering: K a = -R, K b = f,
 *             d lambda = (-c - tau_q . a) / (tau_lambda - tau_q . b), dq = a - d lambda b,
 *             with K factorised by band LU with partial pivoting (K is indefinite on unstable
 *             segments and singular only at isolated critical points, where the step is redone
 *             with another length). Near convergence (residual within 1e3 tolerances and
 *             falling fourfold per iteration) the factorisation of the previous iterate is
 *             reused (chord steps); a corrector whose residual grows past twice its first
 *             value has diverged and is given up at once. The paper uses MGDCM; any
 *             arclength-type method passes the same turning points, and this one reuses the
 *             band factorisation of Newton.
 * Step control: ds grows by 1.5 (to ds_max) after a corrector of at most 5 iterations with a
 * tangent that turned by less than ~6 degrees; it halves (to ds_min) after a failed corrector
 * (iteration cap, NaN, a corrector that moved further than the step itself: a jump to another
 * branch), a tangent that turned by more than acos(turn_cos_min), or a step across which the
 * count of negative eigenvalues changed by more than one (two events in one step are separated).
 *
 * Events. Stability is the count of negative eigenvalues of K (rod_stability.h, verified by
 * shifted refactorisations); no eigenpair is computed at a point where the count does not
 * change. When it changes across a step, the critical point is located on the step length from
 * the last point (each trial point corrected onto the branch) by a safeguarded secant on the
 * critical eigenvalue (the eigenpair nearest zero, shift-invert inverse iteration): each trial
 * goes to the secant root, kept 0.4 locate_tol inside the bracket so that the next one closes
 * it from the other side; bisection when the end eigenvalues do not bracket zero or the bracket
 * did not halve in two trials. The side of a trial is decided by its negative count. It stops
 * when the bracket is narrower than locate_tol in lambda and 10 locate_tol in arclength
 * (typically 3-5 trials; bisection took 15). The eigenvalue nearest zero changes sign across
 * the final bracket. Classification (DESIGN.md section 3) by the C2
 * parity of that critical mode (rod_symmetry.h) and whether the load path folds (the tangent's
 * load component changes sign across the bracket):
 *   parity <= -0.9                -> pitchfork (antisymmetric mode; the symmetric branch goes on)
 *   fold and parity > -0.9        -> saddle-node (turning point in lambda)
 *   no fold, parity >= 0.9        -> symmetric bifurcation (e.g. Euler buckling of a straight rod,
 *                                    whose mode breaks the up-down symmetry, not the C2 one)
 *   otherwise                     -> unclassified
 * Cross-check reported with each event: the mode's projection on f, non-zero at a saddle-node,
 * zero at a pitchfork.
 *
 * Every loop is capped (steps per branch, corrector iterations, location trials, inverse
 * iterations); a branch that cannot be followed ends with a status and a named reason. No NaN
 * is stored in a point or an event. */
#ifndef RIBBON_SIM_ROD_CONTINUE_H
#define RIBBON_SIM_ROD_CONTINUE_H

#include <stddef.h>

#include "rod.h"
#include "rod_load.h"

typedef struct rod_cont_opts {
    double ds;             /* initial arclength step (scaled, see above) */
    double ds_min, ds_max; /* step bounds */
    double lambda_scale;   /* load unit of the arclength (1 for Delta W) */
    double lambda_min;     /* the branch ends when the load leaves [lambda_min, lambda_max] */
    double lambda_max;
    double s_max;          /* the branch ends after this arclength */
    int max_steps;         /* cap on steps (accepted + rejected) per branch */
    int max_corrector;     /* Newton iteration cap per corrector */
    double tolerance;      /* corrector converged when max |R| <= tolerance EI1 / l^2 */
    int max_locate;        /* cap on trial points per event */
    double locate_tol;     /* event bracket width in lambda */
    int max_negative;      /* the branch ends once more eigenvalues than this are negative */
    int eig_max_iter;      /* inverse iteration cap */
    double eig_tol;        /* inverse iteration relative residual */
    double shift_rel;      /* relative shift of the inertia verification */
    double turn_cos_min;   /* a step whose tangent turned more than acos(this) is redone */
} rod_cont_opts;

/* Defaults for the shear path of the paper scenes: ds 0.01, ds in [1e-6, 0.02], lambda in
 * [0, 1], s_max 3, 600 steps, 12 corrector iterations, tolerance 1e-6, 60 trials to 1e-5,
 * max_negative 2, 200 inverse iterations to 1e-8, shift 1e-13, turn_cos_min 0.95. */
rod_cont_opts rod_cont_opts_default(void);

typedef struct rod_cont_point {
    double lambda;         /* load parameter */
    double dl, dw;         /* Delta L, Delta W */
    double dz, a;          /* Delta Z, asymmetry A (rod_observe.h) */
    double energy;         /* J, elastic (+ gravity) energy */
    double s;              /* scaled arclength from the branch start */
    double t_lambda;       /* load component of the unit tangent (changes sign at a fold) */
    int n_negative;        /* negative eigenvalues of the free Hessian */
    int stable;            /* n_negative == 0 */
    int verified;          /* inertia confirmed by the shifted refactorisations */
} rod_cont_point;

typedef enum rod_event_kind {
    ROD_EVENT_SADDLE_NODE = 0,
    ROD_EVENT_PITCHFORK = 1,
    ROD_EVENT_BIFURCATION = 2,
    ROD_EVENT_UNCLASSIFIED = 3
} rod_event_kind;

/* "saddle-node", "pitchfork", "bifurcation", "unclassified". */
const char *rod_event_name(rod_event_kind k);

typedef struct rod_event {
    rod_event_kind kind;
    int branch;            /* id of the branch it lies on */
    int index;             /* branch point just before it */
    rod_cont_point at;     /* the located point: bracket start, with lambda/dl/dw at its middle */
    double lambda_width;   /* final bracket width in lambda */
    double eig_before;     /* eigenvalue nearest zero at the bracket start */
    double eig_after;      /* and at its end (opposite sign when the crossing was resolved) */
    double parity;         /* C2 parity of the critical mode, in [-1, 1] */
    double load_projection;/* |v . f| / |f| of the unit critical mode v */
    int fold;              /* the load path turned within the bracket */
    int n_negative_before, n_negative_after;
    int located;           /* 1: bracket reached locate_tol; 0: location capped or failed */
} rod_event;

#define ROD_CONT_MAX_EVENTS 16

typedef struct rod_branch {
    int id;
    int parent_event;      /* -1, or the event (pitchfork) the branch was switched from */
    rod_cont_point *points;
    size_t n, cap;
    rod_status end_status; /* ROD_OK when it ended at a limit of the options */
    char end_reason[192];  /* why it ended, always set */
} rod_branch;

void rod_branch_free(rod_branch *b);

typedef struct rod_tracer rod_tracer;

/* A tracer for rod r (not owned; its clamps are moved) on load path p. NULL when out of memory. */
rod_tracer *rod_tracer_alloc(rod *r, const rod_load *p, const rod_cont_opts *o);
void rod_tracer_free(rod_tracer *t);

/* Traces a branch from the rod's current equilibrium at load lambda0, initially toward
 * direction (+1: increasing load). Points go to b (b->id set by the caller), events to the
 * tracer's list. Returns ROD_OK when the branch ended at an option limit, otherwise the status
 * of the failure that ended it (b->end_reason says which); the points traced stay valid. */
rod_status rod_trace_branch(rod_tracer *t, double lambda0, int direction, rod_branch *b);

/* Switches at event e (a pitchfork of this tracer's list) onto the branch along sign * mode:
 * corrects the pitchfork state displaced by offset (scaled) along the critical mode onto the
 * hyperplane mode . (Y - Y*) = offset, then traces on from there, away from the pitchfork. */
rod_status rod_trace_switch(rod_tracer *t, int e, double sign, double offset, rod_branch *b);

/* Largest residual (over the force scale EI1 / l^2) of a corrector accepted as stalled: next to
 * a critical point Newton may stop contracting along the nearly singular mode; it is then
 * accepted up to 1e3 times the tolerance, and this reports how far it was (0: never). */
double rod_tracer_worst_residual(const rod_tracer *t);

/* The events found so far, in the order found. */
const rod_event *rod_tracer_events(const rod_tracer *t, int *n);

/* Loads the state kept with event e (the start of its final bracket) into the tracer's rod and
 * returns its load; NAN when e has no stored state. */
double rod_tracer_event_state(rod_tracer *t, int e);

/* The critical mode of event e (rod_nfree values, unit norm) or NULL. */
const double *rod_tracer_mode(const rod_tracer *t, int e);

#endif
