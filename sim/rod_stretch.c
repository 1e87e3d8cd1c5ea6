/* rod_stretch.c: stretching energy of one edge, 1/2 EA (|e|/|e_hat| - 1)^2 |e_hat|.
 * For slender ribbons it acts as a stiff penalty keeping the centreline nearly inextensible. */
#include "rod_kernels.h"
#include "vec3.h"

double rod_stretch_element(const rod *r, int j, double g[6], double H[6][6])
{
    double e[3];
    v3_sub(rod_x(r, j + 1), rod_x(r, j), e);
    double ne = v3_norm(e), l0 = r->len0[j];
    double strain = ne / l0 - 1.0;
    double energy = 0.5 * r->EA * strain * strain * l0;
    if (!g) return energy;
    double t[3];
    v3_scale(e, 1.0 / ne, t);
    /* dE/de = EA strain t */
    for (int k = 0; k < 3; k++) {
        g[k] = -r->EA * strain * t[k];
        g[3 + k] = r->EA * strain * t[k];
    }
    if (!H) return energy;
    /* d2E/de2 = EA / l0 t t^T + EA strain (I - t t^T) / |e| */
    double a = r->EA / l0, b = r->EA * strain / ne;
    for (int p = 0; p < 3; p++)
        for (int q = 0; q < 3; q++) {
            double v = a * t[p] * t[q] + b * ((p == q ? 1.0 : 0.0) - t[p] * t[q]);
            H[p][q] = v;
            H[3 + p][3 + q] = v;
            H[p][3 + q] = -v;
            H[3 + p][q] = -v;
        }
    return energy;
}
