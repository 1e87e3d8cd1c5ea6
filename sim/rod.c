/* rod.c: building a rod from a scene (mesh, stiffnesses, masses, creases) and setting its
 * boundary conditions.
 *
 * Mesh: the free length l is cut into N - 3 edges between the clamp points (node 1 at s = 0,
 * node N-2 at s = 1). With creases at p_L < p_R, the three pieces [0, p_L], [p_L, p_R] and
 * [p_R, 1] are meshed separately with equal edges inside each piece, so that nodes sit exactly
 * on both creases wherever they are (DESIGN.md section 3: edges need not be equal). A mirrored
 * pair (Gamma, 1 - Gamma) gives a mesh symmetric under s -> 1 - s, which keeps the discrete model
 * exactly C2-symmetric; unequal positions give a mesh without symmetry. The clamped edges 0
 * and N-2 lie outside the free length, with the length of their neighbouring free edge.
 * Masses are lumped: each node carries rho A times half of each adjacent rest edge; each twist
 * angle carries the polar inertia rho (I1 + I2) times its edge's rest length. */
#include "rod.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *rod_status_message(rod_status s)
{
    switch (s) {
    case ROD_OK: return "ok";
    case ROD_ERR_ALLOC: return "out of memory";
    case ROD_ERR_SCENE: return "the scene cannot be simulated";
    case ROD_ERR_NAN: return "a non-finite value appeared (NaN detected)";
    case ROD_ERR_SINGULAR: return "singular linear system";
    case ROD_ERR_MAXITER: return "Newton reached its iteration cap without converging";
    case ROD_ERR_LINESEARCH: return "the line search could not reduce the residual (diverged)";
    case ROD_ERR_BRANCH_LOST: return "the requested branch no longer exists";
    case ROD_ERR_TIME_LIMIT: return "the protocol reached its step cap";
    case ROD_ERR_ROUTE_CAP: return "the route reached its cap on static solves";
    }
    return "unknown error";
}

void rod_free(rod *r)
{
    if (!r) return;
    free(r->q); free(r->len0); free(r->vor0); free(r->mass); free(r->s_node);
    free(r->EI1); free(r->kap1_hat); free(r->d1); free(r->d2); free(r->tref); free(r->mref);
    free(r);
}

rod_status rod_alloc(const rod_scene *s, rod **out, char *why, size_t why_len)
{
    char key[64], msg[256];
    *out = NULL;
    if (rod_scene_check(s, msg, sizeof msg, key, sizeof key)) {
        if (why) snprintf(why, why_len, "%s: %s", key, msg);
        return ROD_ERR_SCENE;
    }
    rod *r = calloc(1, sizeof *r);
    if (!r) return ROD_ERR_ALLOC;
    int n = s->nodes;
    r->n = n;
    r->ndof = 4 * n - 1;
    r->free_end = 4 * (n - 2);
    r->length = s->length;
    r->q = calloc((size_t)r->ndof, sizeof *r->q);
    r->len0 = calloc((size_t)n, sizeof *r->len0);
    r->vor0 = calloc((size_t)n, sizeof *r->vor0);
    r->mass = calloc((size_t)r->ndof, sizeof *r->mass);
    r->s_node = calloc((size_t)n, sizeof *r->s_node);
    r->EI1 = calloc((size_t)n, sizeof *r->EI1);
    r->kap1_hat = calloc((size_t)n, sizeof *r->kap1_hat);
    r->d1 = calloc((size_t)n, sizeof *r->d1);
    r->d2 = calloc((size_t)n, sizeof *r->d2);
    r->tref = calloc((size_t)n, sizeof *r->tref);
    r->mref = calloc((size_t)n, sizeof *r->mref);
    if (!r->q || !r->len0 || !r->vor0 || !r->mass || !r->s_node || !r->EI1 || !r->kap1_hat ||
        !r->d1 || !r->d2 || !r->tref || !r->mref) {
        rod_free(r);
        return ROD_ERR_ALLOC;
    }

    int has_folds = rod_scene_has_creases(s);
    double p_left = rod_scene_crease_position(s, 0), p_right = rod_scene_crease_position(s, 1);
    double w = s->width, b = s->thickness, E = s->youngs_modulus;
    double A = w * b, I1 = w * b * b * b / 12.0, I2 = b * w * w * w / 12.0;
    r->rho_area = s->density * A;
    r->rho_polar = s->density * (I1 + I2);
    r->fold_node[0] = r->fold_node[1] = -1;
    if (!has_folds) {
        rod_mesh_set(r, s->fold_position, 0);
    } else if (isnan(s->fold_position_left) && isnan(s->fold_position_right)) {
        rod_mesh_set(r, s->fold_position, rod_mesh_outer_edges(n, s->fold_position)); /* the pair */
    } else if (fabs(p_left + p_right - 1.0) <= 1e-12) {
        rod_mesh_set(r, p_left, rod_mesh_outer_edges(n, p_left)); /* a mirrored pair given by hand */
    } else {
        int nl, nr;
        rod_mesh_crease_edges(n, p_left, p_right, &nl, &nr);
        rod_mesh_set_creases(r, p_left, p_right, nl, nr);
    }
    /* Straight rest configuration along +x, normal +z; th = 0. */
    for (int i = 0; i < n; i++) {
        double *x = rod_x(r, i);
        x[0] = s->length * r->s_node[i];
        x[1] = 0.0;
        x[2] = 0.0;
    }
    for (int i = 0; i < n - 1; i++) {
        double t[3] = {1, 0, 0}, d1[3] = {0, 0, 1}, d2[3] = {0, -1, 0};
        memcpy(r->tref[i], t, sizeof t);
        memcpy(r->d1[i], d1, sizeof d1);
        memcpy(r->d2[i], d2, sizeof d2);
    }

    r->EA = E * A;
    r->EI2 = E * I2;
    r->GJ = s->shear_modulus * w * b * b * b / 3.0;
    for (int i = 0; i < n; i++) r->EI1[i] = E * I1;
    r->force_scale = E * I1 / (s->length * s->length);

    for (int k = 0; k < 3; k++) r->gravity[k] = s->gravity[k];
    r->terms.stretch = 1;
    r->terms.bend = 1;
    r->terms.twist = 1;
    r->terms.fold = has_folds && rod_scene_hinge_rigid(s);
    r->terms.hinge = has_folds && !rod_scene_hinge_rigid(s);
    r->terms.gravity = (s->gravity[0] != 0.0 || s->gravity[1] != 0.0 || s->gravity[2] != 0.0);
    if (has_folds) {
        r->fold_factor = r->terms.fold ? s->fold_stiffness_factor : 1.0;
        r->hinge_k = s->fold_hinge_stiffness;
        if (r->terms.hinge)
            for (int k = 0; k < 2; k++) r->hinge_k_side[k] = rod_scene_hinge_k(s, k);
        /* As rod_set_fold_angle(phi, rel) on a symmetric pair, to the last bit. */
        double rel = s->fold_angle_rel;
        rod_set_crease_angles(r, rod_scene_crease_angle_deg(s, 0) * M_PI / 180.0 * (1.0 + 0.5 * rel),
                              rod_scene_crease_angle_deg(s, 1) * M_PI / 180.0 * (1.0 - 0.5 * rel));
    }
    *out = r;
    return ROD_OK;
}

int rod_mesh_outer_edges(int nodes, double gamma)
{
    int ne_free = nodes - 3;
    int n_out = (int)lround(gamma * ne_free);
    if (n_out < 1) n_out = 1;
    if (ne_free - 2 * n_out < 1) n_out = (ne_free - 1) / 2;
    return n_out;
}

void rod_mesh_crease_edges(int nodes, double p_left, double p_right, int *n_left, int *n_right)
{
    int ne_free = nodes - 3;
    int nl = (int)lround(p_left * ne_free), nr = (int)lround((1.0 - p_right) * ne_free);
    if (nl < 1) nl = 1;
    if (nr < 1) nr = 1;
    while (ne_free - nl - nr < 1 && (nl > 1 || nr > 1)) {
        if (nl >= nr) nl--;
        else nr--;
    }
    *n_left = nl;
    *n_right = nr;
}

/* Rest lengths, Voronoi lengths, clamped edges and lumped masses from the arc-length positions
 * of nodes 1 .. N-2 (s_node[1] = 0, s_node[N-2] = 1). */
static void mesh_rest(rod *r)
{
    int n = r->n;
    double h0 = r->s_node[2] - r->s_node[1];
    r->s_node[0] = -h0;
    r->s_node[n - 1] = 1.0 + h0;
    r->h_clamp = h0 * r->length;
    for (int i = 0; i < n - 1; i++) r->len0[i] = r->length * (r->s_node[i + 1] - r->s_node[i]);
    for (int i = 1; i < n - 1; i++) r->vor0[i] = 0.5 * (r->len0[i - 1] + r->len0[i]);
    /* At the clamp points only the free half of the Voronoi cell bends: counting half of the
     * clamped edge would hold the tangent half an edge outside the clamp and make the rod act as
     * if it were l + h long (measured: buckling load 2% low, elastica heights 0.5% high). */
    r->vor0[1] = 0.5 * r->len0[1];
    r->vor0[n - 2] = 0.5 * r->len0[n - 3];
    memset(r->mass, 0, sizeof(double) * (size_t)r->ndof);
    for (int i = 0; i < n - 1; i++) {
        double m = r->rho_area * r->len0[i];
        for (int k = 0; k < 3; k++) {
            r->mass[4 * i + k] += 0.5 * m;
            r->mass[4 * (i + 1) + k] += 0.5 * m;
        }
        r->mass[4 * i + 3] = r->rho_polar * r->len0[i];
    }
}

void rod_mesh_set(rod *r, double gamma, int n_out)
{
    int n = r->n, ne_free = n - 3;
    /* Arc-length positions of nodes 1..N-2 (over l). */
    if (n_out > 0) {
        int n_mid = ne_free - 2 * n_out;
        double g = gamma;
        for (int k = 0; k <= n_out; k++) r->s_node[1 + k] = g * k / n_out;
        for (int k = 1; k <= n_mid; k++) r->s_node[1 + n_out + k] = g + (1.0 - 2.0 * g) * k / n_mid;
        for (int k = 1; k <= n_out; k++) r->s_node[1 + n_out + n_mid + k] = 1.0 - g + g * k / n_out;
        r->fold_node[0] = 1 + n_out;
        r->fold_node[1] = 1 + n_out + n_mid;
    } else {
        for (int k = 0; k <= ne_free; k++) r->s_node[1 + k] = (double)k / ne_free;
        r->fold_node[0] = r->fold_node[1] = -1;
    }
    r->fold_position = gamma;
    r->fold_position_right = 1.0 - gamma;
    r->fold_outer_edges = n_out;
    r->fold_outer_right = n_out;
    r->s_node[n - 2] = 1.0;
    /* Exact symmetry of the mesh: s_k + s_{N-1-k} = 1. */
    for (int k = 1; k < n / 2; k++) {
        double a = r->s_node[k], b = 1.0 - r->s_node[n - 1 - k];
        double m = 0.5 * (a + b);
        r->s_node[k] = m;
        r->s_node[n - 1 - k] = 1.0 - m;
    }
    if (n % 2 == 1) {
        r->s_node[n / 2] = 0.5;
        r->mid_node = n / 2;
        r->mid_edge = -1;
    } else {
        r->mid_node = -1;
        r->mid_edge = n / 2 - 1;
    }
    r->mid_w = 0.5;
    mesh_rest(r);
}

void rod_mesh_set_creases(rod *r, double p_left, double p_right, int n_left, int n_right)
{
    if (n_left == n_right && fabs(p_left + p_right - 1.0) <= 1e-12) {
        rod_mesh_set(r, p_left, n_left);
        return;
    }
    int n = r->n, ne_free = n - 3, n_mid = ne_free - n_left - n_right;
    for (int k = 0; k <= n_left; k++) r->s_node[1 + k] = p_left * k / n_left;
    for (int k = 1; k <= n_mid; k++) r->s_node[1 + n_left + k] = p_left + (p_right - p_left) * k / n_mid;
    for (int k = 1; k <= n_right; k++) r->s_node[1 + n_left + n_mid + k] = p_right + (1.0 - p_right) * k / n_right;
    r->s_node[1 + n_left] = p_left;
    r->s_node[1 + n_left + n_mid] = p_right;
    r->s_node[n - 2] = 1.0;
    r->fold_node[0] = 1 + n_left;
    r->fold_node[1] = 1 + n_left + n_mid;
    r->fold_position = p_left;
    r->fold_position_right = p_right;
    r->fold_outer_edges = n_left;
    r->fold_outer_right = n_right;
    /* The arc-length midpoint: a node when one sits there, else the edge around it. */
    r->mid_node = -1;
    r->mid_edge = 1;
    r->mid_w = 0.5;
    for (int i = 1; i < n - 2; i++) {
        if (r->s_node[i] == 0.5) {
            r->mid_node = i;
            break;
        }
        if (r->s_node[i] < 0.5 && 0.5 < r->s_node[i + 1]) {
            r->mid_edge = i;
            r->mid_w = (0.5 - r->s_node[i]) / (r->s_node[i + 1] - r->s_node[i]);
        }
    }
    mesh_rest(r);
}

void rod_set_fold_angle(rod *r, double phi, double rel)
{
    rod_set_crease_angles(r, phi * (1.0 + 0.5 * rel), phi * (1.0 - 0.5 * rel));
}

void rod_set_crease_angles(rod *r, double phi_left, double phi_right)
{
    if (!r->terms.fold && !r->terms.hinge) return;
    r->fold_phi[0] = phi_left;
    r->fold_phi[1] = phi_right;
    r->fold_kappa[0] = 2.0 * tan(0.5 * phi_left);
    r->fold_kappa[1] = 2.0 * tan(0.5 * phi_right);
    rod_set_folds(r, 1.0, 1.0);
}

void rod_set_folds(rod *r, double frac_angle, double frac_stiff)
{
    if (!r->terms.fold && !r->terms.hinge) return;
    for (int k = 0; k < 2; k++) {
        int i = r->fold_node[k];
        if (r->terms.hinge) {
            /* The hinge carries the crease (rod_hinge.c); the node's kappa1 term is the hinge's. */
            r->hinge_phi[k] = frac_angle * r->fold_phi[k];
            r->kap1_hat[i] = 0.0;
            r->EI1[i] = r->EI1[0];
            continue;
        }
        /* Ramp the crease angle, not its tangent, so a fraction of the route is a real crease. */
        double phi = 2.0 * atan(0.5 * r->fold_kappa[k]);
        r->kap1_hat[i] = 2.0 * tan(0.5 * phi * frac_angle);
        r->EI1[i] = r->EI1[0] * (1.0 + frac_stiff * (r->fold_factor - 1.0));
    }
}

void rod_set_clamps(rod *r, double dl, double dw)
{
    int n = r->n;
    double l = r->length, h = r->h_clamp;
    double *x0 = rod_x(r, 0), *x1 = rod_x(r, 1), *xa = rod_x(r, n - 2), *xb = rod_x(r, n - 1);
    /* Symmetric loading: each clamp moves by dw l / 2 in opposite directions. It differs from
     * moving one clamp by dw l only by a rigid translation, except that mass-proportional damping
     * acts on absolute velocities; shearing symmetrically keeps the damped dynamics exactly
     * C2-symmetric, so only the imperfection breaks the symmetry. */
    double y = 0.5 * dw * l;
    x0[0] = -h; x0[1] = -y; x0[2] = 0;
    x1[0] = 0; x1[1] = -y; x1[2] = 0;
    xa[0] = l * (1.0 - dl); xa[1] = y; xa[2] = 0;
    xb[0] = l * (1.0 - dl) + h; xb[1] = y; xb[2] = 0;
    r->q[3] = 0.0;
    r->q[4 * (n - 2) + 3] = 0.0;
}
