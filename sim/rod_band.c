/* rod_band.c: band LDL^T without pivoting at half-bandwidth ROD_BAND (see rod_band.h).
 *
 * Right-looking, one column at a time: with d = A(j, j) and l_k = A(j, j + k) / d, the trailing
 * block loses d l l^T, which in band storage touches rows j + 1 .. j + ROD_BAND only:
 *     A(j + k, j + m) -= d l_k l_m,   1 <= k <= m <= ROD_BAND,   stored at row j + k, offset m - k.
 * 55 multiply-adds per column at ROD_BAND = 10; nothing allocates. */
#include "rod_band.h"

#include <math.h>

#define W (ROD_BAND + 1)

int rod_band_ldlt_decomp(double *A, int n)
{
    for (int j = 0; j < n; j++) {
        double *row = A + (size_t)j * W;
        double d = row[0];
        if (!(d != 0.0) || !isfinite(d)) return -1;
        int p = n - 1 - j < ROD_BAND ? n - 1 - j : ROD_BAND;
        double id = 1.0 / d, u[W];
        /* u_k = d l_k = A(j, j + k) (the un-scaled row), then the row becomes l. */
        for (int k = 1; k <= p; k++) {
            u[k] = row[k];
            row[k] *= id;
        }
        if (p == ROD_BAND) {
            for (int k = 1; k <= ROD_BAND; k++) {
                double lk = row[k];
                double *rk = A + (size_t)(j + k) * W - k;
                for (int m = k; m <= ROD_BAND; m++) rk[m] -= lk * u[m];
            }
        } else {
            for (int k = 1; k <= p; k++) {
                double lk = row[k];
                double *rk = A + (size_t)(j + k) * W - k;
                for (int m = k; m <= p; m++) rk[m] -= lk * u[m];
            }
        }
    }
    return 0;
}

void rod_band_ldlt_solve(const double *LD, int n, double *b)
{
    /* L y = b, row by row: y_j = b_j - sum_k L(j, j - k) y_{j - k}, L(j, j - k) stored in row
     * j - k at offset k. (Row-oriented, so each y_j is one dot product and no store waits on the
     * previous row's.) */
    for (int j = 1; j < n; j++) {
        int p = j < ROD_BAND ? j : ROD_BAND;
        double acc = b[j];
        for (int k = 1; k <= p; k++) acc -= LD[(size_t)(j - k) * W + k] * b[j - k];
        b[j] = acc;
    }
    for (int j = 0; j < n; j++) b[j] /= LD[(size_t)j * W];
    /* L^T x = z: row j of L^T holds L(j + k, j) = row[k]. */
    for (int j = n - 1; j >= 0; j--) {
        const double *row = LD + (size_t)j * W;
        int p = n - 1 - j < ROD_BAND ? n - 1 - j : ROD_BAND;
        double x = b[j];
        for (int k = 1; k <= p; k++) x -= row[k] * b[j + k];
        b[j] = x;
    }
}
