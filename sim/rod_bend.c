/* rod_bend.c: bending energy at one interior node, both curvatures, with analytic gradient and
 * Hessian.
 *
 * With e = x_i - x_{i-1}, f = x_{i+1} - x_i, unit tangents te, tf, c = te . tf, chi = 1 + c and
 * material directors (m1, m2) of edges i-1 and i, the two integrated curvatures are
 *     kappa = (a . tf - b . te) / chi,   (a, b) = (m1e, m1f) for kappa1, (m2e, m2f) for kappa2.
 * Derivation (first variations at the current state, frames moved by parallel transport in time,
 * so d a = -(a . d te) te + a' d th_e with a' = d a / d th):
 *     d kappa = Ge . d te + Gf . d tf + (a' . tf / chi) d th_e - (b' . te / chi) d th_f
 *     Ge = (-c a - b - kappa tf) / chi,   Gf = (a + c b - kappa te) / chi,
 * and d te = Je d e with Je = (I - te te^T) / |e|. Differentiating once more gives the blocks
 * below (A_ee, A_ef, A_ff are the derivatives of Ge, Gf with respect to the tangents; the "geo"
 * terms come from differentiating Je). The exact Jacobian of this gradient field is not
 * symmetric: its antisymmetric part is the holonomy of transporting frames along two paths, and
 * its symmetric part is the Hessian of the energy with frames transported from the current
 * state. We return that symmetric part (checked against finite differences in
 * tests/sim/test_rod_derivatives.c). */
#include "rod_kernels.h"
#include "vec3.h"

#include <string.h>

/* H += J A J (all 3x3) */
static void add_JAJ(double H[3][3], double J1[3][3], double A[3][3], double J2[3][3])
{
    double T[3][3];
    m3_mul(J1, A, T);
    m3_mul(T, J2, T);
    for (int p = 0; p < 3; p++)
        for (int q = 0; q < 3; q++) H[p][q] += T[p][q];
}

/* H += -(t . G) / n J - (t g^T + g t^T) / n, g = J G: the derivative of J with respect to e
 * applied to G. */
static void add_geo(double H[3][3], const double t[3], double n, double J[3][3], const double G[3],
                    const double g[3])
{
    double tg = v3_dot(t, G);
    for (int p = 0; p < 3; p++)
        for (int q = 0; q < 3; q++) H[p][q] += -tg / n * J[p][q] - (t[p] * g[q] + g[p] * t[q]) / n;
}

static double curvature_derivs(const double te[3], const double tf[3], double ne, double nf,
                               const double a[3], const double ap[3], const double b[3],
                               const double bp[3], double g8[8], double H8[8][8])
{
    double c = v3_dot(te, tf), chi = 1.0 + c;
    double kap = (v3_dot(a, tf) - v3_dot(b, te)) / chi;
    if (!g8) return kap;
    double Ge[3], Gf[3], ge[3], gf[3], Je[3][3], Jf[3][3];
    for (int k = 0; k < 3; k++) {
        Ge[k] = (-c * a[k] - b[k] - kap * tf[k]) / chi;
        Gf[k] = (a[k] + c * b[k] - kap * te[k]) / chi;
    }
    m3_tangent_jacobian(te, ne, Je);
    m3_tangent_jacobian(tf, nf, Jf);
    m3_apply(Je, Ge, ge);
    m3_apply(Jf, Gf, gf);
    double kte = v3_dot(ap, tf) / chi, ktf = -v3_dot(bp, te) / chi;
    for (int k = 0; k < 3; k++) {
        g8[k] = ge[k];
        g8[3 + k] = gf[k];
    }
    g8[6] = kte;
    g8[7] = ktf;
    if (!H8) return kap;

    double ic = 1.0 / chi;
    double Aee[3][3] = {{0}}, Aef[3][3] = {{0}}, Aff[3][3] = {{0}};
    m3_add_outer(Aee, -ic, a, tf);
    m3_add_outer(Aee, c * ic, te, a);
    m3_add_outer(Aee, -ic, tf, Ge);
    m3_add_outer(Aee, -ic, Ge, tf);
    m3_add_outer(Aef, -ic, a, te);
    m3_add_outer(Aef, ic, tf, b);
    m3_add_outer(Aef, -ic, tf, Gf);
    m3_add_identity(Aef, -kap * ic);
    m3_add_outer(Aef, -ic, Ge, te);
    m3_add_outer(Aff, ic, b, te);
    m3_add_outer(Aff, -c * ic, tf, b);
    m3_add_outer(Aff, -ic, te, Gf);
    m3_add_outer(Aff, -ic, Gf, te);

    double Hee[3][3] = {{0}}, Hef[3][3] = {{0}}, Hff[3][3] = {{0}};
    add_JAJ(Hee, Je, Aee, Je);
    add_geo(Hee, te, ne, Je, Ge, ge);
    add_JAJ(Hef, Je, Aef, Jf);
    add_JAJ(Hff, Jf, Aff, Jf);
    add_geo(Hff, tf, nf, Jf, Gf, gf);

    double v[3], hete[3], hetf[3], hfte[3], hftf[3];
    for (int k = 0; k < 3; k++) v[k] = (-c * ap[k] - kte * tf[k]) * ic;
    m3_apply(Je, v, hete);
    for (int k = 0; k < 3; k++) v[k] = (-bp[k] - ktf * tf[k]) * ic;
    m3_apply(Je, v, hetf);
    for (int k = 0; k < 3; k++) v[k] = (ap[k] - kte * te[k]) * ic;
    m3_apply(Jf, v, hfte);
    for (int k = 0; k < 3; k++) v[k] = (c * bp[k] - ktf * te[k]) * ic;
    m3_apply(Jf, v, hftf);

    memset(H8, 0, sizeof(double) * 64);
    for (int p = 0; p < 3; p++) {
        for (int q = 0; q < 3; q++) {
            H8[p][q] = 0.5 * (Hee[p][q] + Hee[q][p]);
            H8[3 + p][3 + q] = 0.5 * (Hff[p][q] + Hff[q][p]);
            H8[p][3 + q] = Hef[p][q];
            H8[3 + q][p] = Hef[p][q];
        }
        H8[p][6] = H8[6][p] = hete[p];
        H8[p][7] = H8[7][p] = hetf[p];
        H8[3 + p][6] = H8[6][3 + p] = hfte[p];
        H8[3 + p][7] = H8[7][3 + p] = hftf[p];
    }
    H8[6][6] = -v3_dot(a, tf) * ic;
    H8[7][7] = v3_dot(b, te) * ic;
    return kap;
}

void rod_local_from_ef(double s, const double g8[8], double H8[8][8], double g[11], double H[11][11])
{
    /* Local index -> up to two (index in 8-space, coefficient) pairs. */
    static const int idx[11][2] = {{0, -1}, {1, -1}, {2, -1}, {6, -1}, {0, 3}, {1, 4},
                                   {2, 5},  {7, -1}, {3, -1}, {4, -1}, {5, -1}};
    static const double co[11][2] = {{-1, 0}, {-1, 0}, {-1, 0}, {1, 0}, {1, -1}, {1, -1},
                                     {1, -1}, {1, 0},  {1, 0},  {1, 0}, {1, 0}};
    if (g)
        for (int l = 0; l < 11; l++) {
            double v = co[l][0] * g8[idx[l][0]];
            if (idx[l][1] >= 0) v += co[l][1] * g8[idx[l][1]];
            g[l] += s * v;
        }
    if (H)
        for (int l = 0; l < 11; l++)
            for (int m = 0; m < 11; m++) {
                double v = 0.0;
                for (int a = 0; a < 2; a++) {
                    if (a == 1 && idx[l][1] < 0) break;
                    for (int b = 0; b < 2; b++) {
                        if (b == 1 && idx[m][1] < 0) break;
                        v += co[l][a] * co[m][b] * H8[idx[l][a]][idx[m][b]];
                    }
                }
                H[l][m] += s * v;
            }
}

static void node_geometry(const rod *r, int i, double te[3], double tf[3], double *ne, double *nf)
{
    double e[3], f[3];
    v3_sub(rod_x(r, i), rod_x(r, i - 1), e);
    v3_sub(rod_x(r, i + 1), rod_x(r, i), f);
    *ne = v3_norm(e);
    *nf = v3_norm(f);
    v3_scale(e, 1.0 / *ne, te);
    v3_scale(f, 1.0 / *nf, tf);
}

/* The kappa1 term at node i: a compliant hinge's (rod_hinge.c) or the strip's
 * 1/2 K1 (kappa1 - kappa1_hat)^2 when the rod bends; energy, and the first and second
 * derivatives in kappa1 into *w and *c. */
static double kappa1_term(const rod *r, int i, double k1, double K1, double *w, double *c)
{
    double e;
    if (rod_hinge_kappa1(r, i, k1, &e, w, c)) return e;
    if (!r->terms.bend) {
        *w = *c = 0.0;
        return 0.0;
    }
    double d1 = k1 - r->kap1_hat[i];
    *w = K1 * d1;
    *c = K1;
    return 0.5 * K1 * d1 * d1;
}

double rod_bend_element(const rod *r, int i, double g[11], double H[11][11])
{
    double te[3], tf[3], ne, nf, m1e[3], m2e[3], m1f[3], m2f[3], nm1e[3], nm1f[3];
    node_geometry(r, i, te, tf, &ne, &nf);
    rod_material_frame(r, i - 1, m1e, m2e);
    rod_material_frame(r, i, m1f, m2f);
    v3_scale(m1e, -1.0, nm1e);
    v3_scale(m1f, -1.0, nm1f);
    double w = 1.0 / r->vor0[i];
    double K1 = r->EI1[i] * w, K2 = r->terms.bend ? r->EI2 * w : 0.0;
    double g1[8], g2[8], H1[8][8], H2[8][8];
    double k1 = curvature_derivs(te, tf, ne, nf, m1e, m2e, m1f, m2f, g ? g1 : NULL, H ? H1 : NULL);
    double k2 = curvature_derivs(te, tf, ne, nf, m2e, nm1e, m2f, nm1f, g ? g2 : NULL, H ? H2 : NULL);
    double w1, c1;
    double energy = kappa1_term(r, i, k1, K1, &w1, &c1) + 0.5 * K2 * k2 * k2;
    if (!g) return energy;
    double G8[8], HH[8][8];
    for (int a = 0; a < 8; a++) G8[a] = w1 * g1[a] + K2 * k2 * g2[a];
    if (H)
        for (int a = 0; a < 8; a++)
            for (int b = 0; b < 8; b++)
                HH[a][b] = c1 * g1[a] * g1[b] + w1 * H1[a][b] + K2 * (g2[a] * g2[b] + k2 * H2[a][b]);
    memset(g, 0, sizeof(double) * 11);
    if (H) memset(H, 0, sizeof(double) * 121);
    rod_local_from_ef(1.0, G8, H ? HH : NULL, g, H);
    return energy;
}

double rod_twist_element(const rod *r, int i, double g[11], double H[11][11])
{
    double te[3], tf[3], ne, nf;
    node_geometry(r, i, te, tf, &ne, &nf);
    double K = r->GJ / r->vor0[i];
    double k3 = rod_theta(r, i) - rod_theta(r, i - 1) + r->mref[i];
    double energy = 0.5 * K * k3 * k3;
    if (!g) return energy;
    /* Reference twist gradient (holonomy of the transported frames): dm/de = kb / (2 |e|),
     * dm/df = kb / (2 |f|), kb = 2 te x tf / chi. */
    double c = v3_dot(te, tf), chi = 1.0 + c, kb[3];
    v3_cross(te, tf, kb);
    v3_scale(kb, 2.0 / chi, kb);
    double g8[8];
    for (int k = 0; k < 3; k++) {
        g8[k] = 0.5 * kb[k] / ne;
        g8[3 + k] = 0.5 * kb[k] / nf;
    }
    g8[6] = -1.0;
    g8[7] = 1.0;
    double G8[8], HH[8][8];
    for (int a = 0; a < 8; a++) G8[a] = K * k3 * g8[a];
    if (H) {
        /* d kb = (-2 [tf]x - kb tf^T) / chi d te + (2 [te]x - kb te^T) / chi d tf */
        double Kbe[3][3] = {{0}}, Kbf[3][3] = {{0}}, Je[3][3], Jf[3][3];
        m3_add_cross(Kbe, -2.0 / chi, tf);
        m3_add_outer(Kbe, -1.0 / chi, kb, tf);
        m3_add_cross(Kbf, 2.0 / chi, te);
        m3_add_outer(Kbf, -1.0 / chi, kb, te);
        m3_tangent_jacobian(te, ne, Je);
        m3_tangent_jacobian(tf, nf, Jf);
        double Mee[3][3], Mef[3][3], Mfe[3][3], Mff[3][3];
        m3_mul(Kbe, Je, Mee);
        m3_mul(Kbf, Jf, Mef);
        m3_mul(Kbe, Je, Mfe);
        m3_mul(Kbf, Jf, Mff);
        double Hm[6][6];
        for (int p = 0; p < 3; p++)
            for (int q = 0; q < 3; q++) {
                Hm[p][q] = 0.5 * Mee[p][q] / ne - 0.5 * kb[p] * te[q] / (ne * ne);
                Hm[p][3 + q] = 0.5 * Mef[p][q] / ne;
                Hm[3 + p][q] = 0.5 * Mfe[p][q] / nf;
                Hm[3 + p][3 + q] = 0.5 * Mff[p][q] / nf - 0.5 * kb[p] * tf[q] / (nf * nf);
            }
        for (int a = 0; a < 8; a++)
            for (int b = 0; b < 8; b++) {
                double hm = 0.0;
                if (a < 6 && b < 6) hm = 0.5 * (Hm[a][b] + Hm[b][a]);
                HH[a][b] = K * (g8[a] * g8[b] + k3 * hm);
            }
    }
    memset(g, 0, sizeof(double) * 11);
    if (H) memset(H, 0, sizeof(double) * 121);
    rod_local_from_ef(1.0, G8, H ? HH : NULL, g, H);
    return energy;
}

/* Gradient only of one curvature (the first half of curvature_derivs): g8 overwritten. */
static double curvature_grad(const double te[3], const double tf[3], double c, double ne, double nf,
                             const double a[3], const double ap[3], const double b[3], const double bp[3],
                             double g8[8])
{
    double ic = 1.0 / (1.0 + c);
    double kap = (v3_dot(a, tf) - v3_dot(b, te)) * ic;
    double Ge[3], Gf[3];
    for (int k = 0; k < 3; k++) {
        Ge[k] = (-c * a[k] - b[k] - kap * tf[k]) * ic;
        Gf[k] = (a[k] + c * b[k] - kap * te[k]) * ic;
    }
    /* J G = (G - t (t . G)) / n */
    double se = v3_dot(te, Ge), sf = v3_dot(tf, Gf);
    for (int k = 0; k < 3; k++) {
        g8[k] = (Ge[k] - se * te[k]) / ne;
        g8[3 + k] = (Gf[k] - sf * tf[k]) / nf;
    }
    g8[6] = v3_dot(ap, tf) * ic;
    g8[7] = -v3_dot(bp, te) * ic;
    return kap;
}

/* The node element in (e, f, th_e, th_f) space: bending and twist at interior node i plus the
 * stretching of edge i-1 (which depends on e alone), each as the scene's terms ask.
 *
 * Why one kernel: the three terms share the edge geometry (tangents, lengths, the projectors
 * J) and the 8 -> 11 map to the local DOFs, and the bending Hessian needs only one second-
 * derivative pass: with weights w1 = K1 (kappa1 - kappa1_hat), w2 = K2 kappa2,
 *     Hess E_bend = K1 g1 g1^T + K2 g2 g2^T + w1 Hess kappa1 + w2 Hess kappa2,
 * and Hess kappa (curvature_derivs) is linear in the directors (a, a', b, b'), so
 * w1 Hess kappa1 + w2 Hess kappa2 is Hess kappa evaluated with the combined directors
 * a = w1 m1e + w2 m2e, a' = w1 m2e - w2 m1e (and the same for b): the same numbers as
 * rod_bend_element up to round-off, at about half the cost. Its gradient is w1 g1 + w2 g2.
 * At a compliant crease (rod_hinge.c) the kappa1 term is the hinge's, E(kappa1): w1 = E' and
 * the g1 g1^T coefficient K1 becomes E''.
 * Returns the energy; g8 and H8 (may be NULL) are overwritten. */
double rod_node_ef(const rod *r, int i, const double mf_e[6], const double mf_f[6], double g8[8],
                   double H8[8][8])
{
    double te[3], tf[3], ne, nf;
    node_geometry(r, i, te, tf, &ne, &nf);
    double c = v3_dot(te, tf), chi = 1.0 + c, energy = 0.0;
    for (int a = 0; a < 8; a++) g8[a] = 0.0;
    if (H8) memset(H8, 0, sizeof(double) * 64);

    if (r->terms.stretch) {
        double l0 = r->len0[i - 1], strain = ne / l0 - 1.0;
        energy += 0.5 * r->EA * strain * strain * l0;
        for (int k = 0; k < 3; k++) g8[k] += r->EA * strain * te[k];
        if (H8) {
            double a = r->EA / l0, b = r->EA * strain / ne;
            for (int p = 0; p < 3; p++)
                for (int q = 0; q < 3; q++)
                    H8[p][q] += a * te[p] * te[q] + b * ((p == q ? 1.0 : 0.0) - te[p] * te[q]);
        }
    }

    int hinge = r->terms.hinge && (i == r->fold_node[0] || i == r->fold_node[1]);
    if (r->terms.bend || hinge) {
        double m1e[3], m2e[3], m1f[3], m2f[3], nm1e[3], nm1f[3];
        if (mf_e) {
            for (int k = 0; k < 3; k++) {
                m1e[k] = mf_e[k], m2e[k] = mf_e[3 + k];
                m1f[k] = mf_f[k], m2f[k] = mf_f[3 + k];
            }
        } else {
            rod_material_frame(r, i - 1, m1e, m2e);
            rod_material_frame(r, i, m1f, m2f);
        }
        v3_scale(m1e, -1.0, nm1e);
        v3_scale(m1f, -1.0, nm1f);
        double w = 1.0 / r->vor0[i];
        double K1 = r->EI1[i] * w, K2 = r->terms.bend ? r->EI2 * w : 0.0;
        double g1[8], g2[8];
        double k1 = curvature_grad(te, tf, c, ne, nf, m1e, m2e, m1f, m2f, g1);
        double k2 = curvature_grad(te, tf, c, ne, nf, m2e, nm1e, m2f, nm1f, g2);
        double w1, c1;
        if (hinge) {
            double e1;
            rod_hinge_kappa1(r, i, k1, &e1, &w1, &c1);
            energy += e1 + 0.5 * K2 * k2 * k2;
        } else {
            double d1 = k1 - r->kap1_hat[i];
            energy += 0.5 * K1 * d1 * d1 + 0.5 * K2 * k2 * k2;
            w1 = K1 * d1;
            c1 = K1;
        }
        double w2 = K2 * k2;
        for (int a = 0; a < 8; a++) g8[a] += w1 * g1[a] + w2 * g2[a];
        if (H8) {
            double A[3], Ap[3], B[3], Bp[3], gc[8], Hc[8][8];
            for (int k = 0; k < 3; k++) {
                A[k] = w1 * m1e[k] + w2 * m2e[k];
                Ap[k] = w1 * m2e[k] - w2 * m1e[k];
                B[k] = w1 * m1f[k] + w2 * m2f[k];
                Bp[k] = w1 * m2f[k] - w2 * m1f[k];
            }
            curvature_derivs(te, tf, ne, nf, A, Ap, B, Bp, gc, Hc);
            for (int a = 0; a < 8; a++)
                for (int b = 0; b < 8; b++) H8[a][b] += c1 * g1[a] * g1[b] + K2 * g2[a] * g2[b] + Hc[a][b];
        }
    }

    if (r->terms.twist) {
        double K = r->GJ / r->vor0[i];
        double k3 = rod_theta(r, i) - rod_theta(r, i - 1) + r->mref[i];
        energy += 0.5 * K * k3 * k3;
        /* As rod_twist_element: d m_ref / de = kb / (2 |e|), d m_ref / df = kb / (2 |f|). */
        double kb[3], gt[8];
        v3_cross(te, tf, kb);
        v3_scale(kb, 2.0 / chi, kb);
        for (int k = 0; k < 3; k++) {
            gt[k] = 0.5 * kb[k] / ne;
            gt[3 + k] = 0.5 * kb[k] / nf;
        }
        gt[6] = -1.0;
        gt[7] = 1.0;
        for (int a = 0; a < 8; a++) g8[a] += K * k3 * gt[a];
        if (H8) {
            double Kbe[3][3] = {{0}}, Kbf[3][3] = {{0}}, Je[3][3], Jf[3][3], Me[3][3], Mf[3][3];
            m3_add_cross(Kbe, -2.0 / chi, tf);
            m3_add_outer(Kbe, -1.0 / chi, kb, tf);
            m3_add_cross(Kbf, 2.0 / chi, te);
            m3_add_outer(Kbf, -1.0 / chi, kb, te);
            m3_tangent_jacobian(te, ne, Je);
            m3_tangent_jacobian(tf, nf, Jf);
            m3_mul(Kbe, Je, Me);
            m3_mul(Kbf, Jf, Mf);
            double s = K * k3;
            for (int p = 0; p < 3; p++)
                for (int q = 0; q < 3; q++) {
                    /* The symmetric part of d(gt)/d(e, f), as rod_twist_element. */
                    double hee = 0.5 * Me[p][q] / ne - 0.5 * kb[p] * te[q] / (ne * ne);
                    double hee_t = 0.5 * Me[q][p] / ne - 0.5 * kb[q] * te[p] / (ne * ne);
                    double hff = 0.5 * Mf[p][q] / nf - 0.5 * kb[p] * tf[q] / (nf * nf);
                    double hff_t = 0.5 * Mf[q][p] / nf - 0.5 * kb[q] * tf[p] / (nf * nf);
                    /* (e row p, f col q): 1/2 (d gt_e[p] / df_q + d gt_f[q] / de_p) */
                    double hef = 0.5 * (0.5 * Mf[p][q] / ne + 0.5 * Me[q][p] / nf);
                    H8[p][q] += s * 0.5 * (hee + hee_t);
                    H8[3 + p][3 + q] += s * 0.5 * (hff + hff_t);
                    H8[p][3 + q] += s * hef;
                    H8[3 + q][p] += s * hef;
                }
            for (int a = 0; a < 8; a++)
                for (int b = 0; b < 8; b++) H8[a][b] += K * gt[a] * gt[b];
        }
    }
    return energy;
}
