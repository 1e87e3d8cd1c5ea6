/* rod_stability.h: stability of a rod equilibrium from its free-DOF Hessian in symmetric band
 * storage (rod.h: H[i (ROD_BAND + 1) + (j - i)] holds A(i, j) for i <= j <= i + ROD_BAND).
 *
 * Inertia. By Sylvester's law of inertia the number of negative eigenvalues of A equals the
 * number of negative pivots of any factorisation A = L D L^T (L unit lower triangular). The band
 * LDL^T here does not pivot (neither does GSL's), so on an indefinite matrix a tiny pivot can
 * grow the factor and make a pivot's sign unreliable. Production therefore factorises three
 * times: A, A - sigma I and A + sigma I with sigma a small multiple of max |A_ii| (DESIGN.md
 * section 4). The shifted counts are the eigenvalues below +sigma and below -sigma; when they
 * agree no eigenvalue lies within sigma of zero and the count is trusted ("verified" when the
 * unshifted count agrees too). When they differ an eigenvalue sits within sigma of zero: the
 * state is critical to working precision and the unshifted count is reported with near_singular
 * set. Tests cross-check against dense eigenvalues (gsl_eigen_symm).
 *
 * Eigenpair. The eigenvalue nearest a shift sigma and its eigenvector by shift-invert inverse
 * iteration: factor A - sigma I once (GSL band LU with partial pivoting, which is stable on
 * indefinite matrices), then repeat v <- (A - sigma I)^-1 v / |.|, with the Rayleigh quotient
 * as the eigenvalue. Converged when |A v - mu v| <= rel_tol |mu - sigma| + 1e-14 max |A_ii|
 * (the second term is the round-off floor of a band matrix-vector product), or when the
 * Rayleigh quotient stops changing to 1e-13; capped at max_iter iterations. Near a critical
 * point (the shift 0, one eigenvalue near 0) it converges in a few iterations.
 *
 * Units: the free DOFs mix positions (m) and angles (rad), so eigenvalues mix N/m and N m; the
 * inertia (and the sign of a crossing eigenvalue) does not depend on that choice of units. */
#ifndef RIBBON_SIM_ROD_STABILITY_H
#define RIBBON_SIM_ROD_STABILITY_H

#include "rod.h"

typedef struct rod_stab_ws rod_stab_ws;

/* Workspace for matrices of n free DOFs; NULL when out of memory. */
rod_stab_ws *rod_stab_ws_alloc(int n);
void rod_stab_ws_free(rod_stab_ws *w);

/* Counts the negative pivots of the LDL^T factorisation (no pivoting) of A - shift I, A given
 * in symmetric band storage (n rows, half-bandwidth ROD_BAND). A is not modified. A zero pivot
 * makes the factorisation fail: returns -1. *min_pivot_rel (may be NULL) receives the smallest
 * |pivot| over max |A_ii|. */
int rod_band_negative_pivots(const double *A, int n, double shift, rod_stab_ws *w, double *min_pivot_rel);

typedef struct rod_inertia {
    int n_negative;       /* negative eigenvalues of A (see near_singular) */
    int below_plus;       /* eigenvalues below +shift (pivots of A - shift I) */
    int below_minus;      /* eigenvalues below -shift (pivots of A + shift I) */
    double shift;         /* sigma = shift_rel max |A_ii| */
    double min_pivot_rel; /* smallest |pivot| / max |A_ii| of the unshifted factorisation */
    int verified;         /* the three counts agree: no eigenvalue within sigma of zero */
    int near_singular;    /* the shifted counts differ: an eigenvalue lies within sigma of 0 */
} rod_inertia;

/* Default relative shift of the verification (1e-13: at the paper scene max |A_ii| ~ 1e8, so
 * sigma ~ 1e-5, far below the soft eigenvalues ~ 1e-2 of a stable arch). */
#define ROD_INERTIA_SHIFT_REL 1e-13

/* Inertia of A with the shifted verification above. Fails with ROD_ERR_SINGULAR (and a reason)
 * only when all three factorisations hit an exact zero pivot, and ROD_ERR_NAN on a non-finite
 * entry. */
rod_status rod_inertia_eval(const double *A, int n, double shift_rel, rod_stab_ws *w, rod_inertia *out,
                            char *why, size_t why_len);

/* y = A x for A in symmetric band storage. */
void rod_band_symv(const double *A, int n, const double *x, double *y);

typedef struct rod_eigpair {
    double value;      /* eigenvalue nearest the shift */
    double residual;   /* |A v - value v| */
    int iterations;
} rod_eigpair;

/* Eigenvalue of A nearest sigma and its unit eigenvector v (n values; on entry a start vector,
 * or all zeros for the built-in start, which has components on every mode). Returns
 * ROD_ERR_SINGULAR when A - sigma I cannot be factorised even after nudging sigma,
 * ROD_ERR_MAXITER after max_iter iterations, ROD_ERR_NAN on non-finite values; why (may be
 * NULL) receives the reason. */
rod_status rod_eig_nearest(const double *A, int n, double sigma, int max_iter, double rel_tol, rod_stab_ws *w,
                           double *v, rod_eigpair *out, char *why, size_t why_len);

#endif
