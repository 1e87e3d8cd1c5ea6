/* rod_load.h: a one-parameter load path of the clamps and its load vector, what continuation
 * differentiates along.
 *
 * The clamps are prescribed displacements (rod_set_clamps), so the "load" of the paper's
 * R(q, lambda) = 0 is not a force: it is the clamp configuration. On the shear path lambda is
 * Delta W at fixed Delta L (the protocol, DESIGN.md section 3); on the compression path lambda is
 * Delta L at fixed Delta W (used for the Euler buckling check). The load vector is
 *
 *     f = dR_free / dlambda = H(free, clamped) dq_clamped / dlambda,
 *
 * the coupling block of the Hessian between free and prescribed DOFs times the clamp velocity
 * (DESIGN.md section 3: "the derivative of the residual with respect to Delta W, not a force
 * applied at the clamp"). Only elements that touch a moving clamp DOF contribute (at most four
 * node elements and two edges), so it costs O(1) kernel calls. Tests check it against central
 * differences of the gradient. */
#ifndef RIBBON_SIM_ROD_LOAD_H
#define RIBBON_SIM_ROD_LOAD_H

#include "rod.h"

typedef enum rod_load_kind {
    ROD_LOAD_SHEAR = 0,      /* lambda = Delta W, Delta L held */
    ROD_LOAD_COMPRESSION = 1 /* lambda = Delta L, Delta W held */
} rod_load_kind;

typedef struct rod_load {
    rod_load_kind kind;
    double dl;   /* Delta L held on the shear path */
    double dw;   /* Delta W held on the compression path */
} rod_load;

/* Places the clamps at load lambda (twist angles of the clamped edges zero). Frames are not
 * updated. */
void rod_load_apply(rod *r, const rod_load *p, double lambda);

/* Delta L and Delta W at load lambda. */
void rod_load_clamps(const rod_load *p, double lambda, double *dl, double *dw);

/* The load vector f (rod_nfree(r) values, overwritten) at the current state; frames must be up
 * to date. */
void rod_load_vector(const rod *r, const rod_load *p, double *f);

#endif
