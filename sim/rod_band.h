/* rod_band.h: LDL^T of a symmetric band matrix of half-bandwidth ROD_BAND, without pivoting,
 * for the Newton steps of rod_solver.c.
 *
 * Why not GSL's gsl_linalg_ldlt_band_decomp: it is the same algorithm, but written for any
 * bandwidth it makes a matrix view and a CBLAS dsyr call per column and estimates the 1-norm
 * for a condition number we do not use; at ROD_BAND = 10 that overhead is most of its time
 * (profile: dsyr, dasum, dscal and the views were a quarter of a paper prediction). With the
 * bandwidth a compile-time constant the loops below unroll and vectorise.
 *
 * Storage (rod.h): A[i (ROD_BAND + 1) + k] = A(i, i + k) for 0 <= k <= ROD_BAND, i + k < n.
 * After rod_band_ldlt_decomp the same array holds D(i) at k = 0 and L(i + k, i) at k >= 1
 * (L unit lower triangular), so A = L D L^T. As with any LDL^T without pivoting, it is stable
 * for positive definite matrices; on indefinite ones a pivot may be tiny, which callers check
 * (rod_solver.c falls back to band LU with partial pivoting). */
#ifndef RIBBON_SIM_ROD_BAND_H
#define RIBBON_SIM_ROD_BAND_H

#include "rod.h"

/* Factorises A (n rows) in place. Returns 0, or -1 when a pivot is zero or not finite (A is then
 * partly overwritten). */
int rod_band_ldlt_decomp(double *A, int n);

/* Solves A x = b in place (b becomes x) with the factors from rod_band_ldlt_decomp. */
void rod_band_ldlt_solve(const double *LD, int n, double *b);

#endif
