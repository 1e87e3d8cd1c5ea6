/* vec3.h: tiny inline 3-vector and 3x3 helpers for the rod kernels. Plain arrays (double[3],
 * double[3][3], row-major) so kernels stay allocation-free and readable. */
#ifndef RIBBON_SIM_VEC3_H
#define RIBBON_SIM_VEC3_H

#include <math.h>

static inline double v3_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void v3_cross(const double a[3], const double b[3], double out[3])
{
    double t0 = a[1] * b[2] - a[2] * b[1];
    double t1 = a[2] * b[0] - a[0] * b[2];
    double t2 = a[0] * b[1] - a[1] * b[0];
    out[0] = t0; out[1] = t1; out[2] = t2;
}
static inline double v3_norm(const double a[3]) { return sqrt(v3_dot(a, a)); }
static inline void v3_sub(const double a[3], const double b[3], double out[3])
{
    out[0] = a[0] - b[0]; out[1] = a[1] - b[1]; out[2] = a[2] - b[2];
}
static inline void v3_scale(const double a[3], double s, double out[3])
{
    out[0] = a[0] * s; out[1] = a[1] * s; out[2] = a[2] * s;
}
/* out = a + s b */
static inline void v3_axpy(const double a[3], double s, const double b[3], double out[3])
{
    out[0] = a[0] + s * b[0]; out[1] = a[1] + s * b[1]; out[2] = a[2] + s * b[2];
}
static inline void v3_copy(const double a[3], double out[3])
{
    out[0] = a[0]; out[1] = a[1]; out[2] = a[2];
}
/* M += s a b^T */
static inline void m3_add_outer(double M[3][3], double s, const double a[3], const double b[3])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) M[i][j] += s * a[i] * b[j];
}
/* M += s I */
static inline void m3_add_identity(double M[3][3], double s)
{
    M[0][0] += s; M[1][1] += s; M[2][2] += s;
}
/* M += s [a]_x (the matrix with [a]_x v = a x v) */
static inline void m3_add_cross(double M[3][3], double s, const double a[3])
{
    M[0][1] -= s * a[2]; M[0][2] += s * a[1];
    M[1][0] += s * a[2]; M[1][2] -= s * a[0];
    M[2][0] -= s * a[1]; M[2][1] += s * a[0];
}
/* out = A B */
static inline void m3_mul(double A[3][3], double B[3][3], double out[3][3])
{
    double t[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) t[i][j] = A[i][0] * B[0][j] + A[i][1] * B[1][j] + A[i][2] * B[2][j];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) out[i][j] = t[i][j];
}
/* out = A v */
static inline void m3_apply(double A[3][3], const double v[3], double out[3])
{
    double t0 = A[0][0] * v[0] + A[0][1] * v[1] + A[0][2] * v[2];
    double t1 = A[1][0] * v[0] + A[1][1] * v[1] + A[1][2] * v[2];
    double t2 = A[2][0] * v[0] + A[2][1] * v[1] + A[2][2] * v[2];
    out[0] = t0; out[1] = t1; out[2] = t2;
}
/* P = (I - t t^T) / n: derivative of the unit tangent t = e/|e| with respect to e (n = |e|). */
static inline void m3_tangent_jacobian(const double t[3], double n, double P[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) P[i][j] = ((i == j ? 1.0 : 0.0) - t[i] * t[j]) / n;
}
#endif
