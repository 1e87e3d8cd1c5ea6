/* predict_ladder.c: resolution ladder of a scene's prediction (see predict_ladder.h). */
#include "predict_ladder.h"

#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "rod_protocol.h"

static uint64_t fnv(uint64_t h, const char *s)
{
    for (; *s; s++) {
        h ^= (unsigned char)*s;
        h *= 1099511628211ull;
    }
    return h;
}

void predict_scene_hash(const rod_scene *sc, char out[17])
{
    char buf[1024];
    /* Every field but the mesh size, printed exactly (%a), so equal scenes hash equal. */
    snprintf(buf, sizeof buf,
             "%a %a %a %a %a %a %a %a %a|%a %a %a|%a|%a %a %a %d|%a %a %a %d|%a %a",
             sc->length, sc->width, sc->thickness, sc->youngs_modulus, sc->shear_modulus, sc->density,
             sc->gravity[0], sc->gravity[1], sc->gravity[2], sc->fold_angle_deg, sc->fold_position,
             sc->fold_stiffness_factor, sc->fold_angle_rel, sc->compression, sc->shear_rate, sc->shear_max,
             (int)sc->route, sc->dt, sc->damping, sc->tolerance, sc->max_iterations, sc->snap_speed,
             sc->asym_threshold);
    /* Each crease's own values and a compliant hinge (issue 31), appended only when set, so a
     * scene without them keeps the hash (and the stored ladders) it had. */
    if (!isnan(sc->fold_angle_left_deg) || !isnan(sc->fold_angle_right_deg) || !isnan(sc->fold_position_left) ||
        !isnan(sc->fold_position_right) || !rod_scene_hinge_rigid(sc)) {
        size_t used = strlen(buf);
        snprintf(buf + used, sizeof buf - used, "|%a %a %a %a %a", sc->fold_angle_left_deg, sc->fold_angle_right_deg,
                 sc->fold_position_left, sc->fold_position_right, sc->fold_hinge_stiffness);
    }
    /* Each crease's own hinge (issue 32), appended only when set, for the same reason. */
    if (!isnan(sc->fold_hinge_stiffness_left) || !isnan(sc->fold_hinge_stiffness_right)) {
        size_t used = strlen(buf);
        snprintf(buf + used, sizeof buf - used, "|k %a %a", sc->fold_hinge_stiffness_left, sc->fold_hinge_stiffness_right);
    }
    uint64_t h = fnv(1469598103934665603ull, buf);
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}

double predict_ladder_dt(double dt_finest, int finest_nodes, int nodes)
{
    return dt_finest * (double)(finest_nodes - 3) / (double)(nodes - 3);
}

void predict_ladder_estimate_errors(predict_ladder_rung *r, int n, rod_ladder_verdict *verdict)
{
    double h[PREDICT_LADDER_MAX_RUNGS] = {0}, s[PREDICT_LADDER_MAX_RUNGS] = {0}, err[PREDICT_LADDER_MAX_RUNGS];
    if (n > PREDICT_LADDER_MAX_RUNGS) n = PREDICT_LADDER_MAX_RUNGS;
    if (n < 0) n = 0;
    for (int k = 0; k < n; k++) {
        h[k] = 1.0 / (double)(r[k].nodes - 3); /* edge length over l */
        s[k] = r[k].snap_dw;
    }
    rod_ladder_estimate(h, s, n, err, verdict);
    for (int k = 0; k < n; k++) r[k].est_error = err[k];
}

/* rod_predict's per-step callback: stops the rung once the cancel flag is set. */
static int stop_if_cancelled(void *user, const rod_sample *smp, const rod *r)
{
    (void)smp;
    (void)r;
    const atomic_int *cancel = user;
    return cancel && atomic_load(cancel);
}

double predict_estimate_s(const rod_scene *sc, int adaptive)
{
    if (!(sc->shear_rate > 0) || !(sc->dt > 0)) return INFINITY;
    double steps = sc->shear_max * sc->length / (sc->shear_rate * sc->dt); /* shear time / dt */
    if (adaptive) steps /= PREDICT_FAST_STEP_RATIO;
    return steps * (double)sc->nodes * PREDICT_STEP_NODE_S;
}

double predict_ladder_estimate_s(const rod_scene *sc, const int *nodes, int n, int adaptive)
{
    double total = 0.0;
    for (int k = 0; k < n; k++) {
        rod_scene s = *sc;
        s.nodes = nodes[k];
        s.dt = predict_ladder_dt(sc->dt, nodes[n - 1], nodes[k]);
        total += predict_estimate_s(&s, adaptive);
    }
    return total;
}

int predict_ladder_compute(const rod_scene *sc, const int *nodes, int n, int adaptive, predict_ladder_rung *out,
                           rod_ladder_verdict *verdict,
                           void (*progress)(void *user, const predict_ladder_rung *r, int k, int n), void *user,
                           const atomic_int *cancel, char *why, size_t why_len)
{
    if (n < 1 || n > PREDICT_LADDER_MAX_RUNGS) {
        snprintf(why, why_len, "a ladder needs 1 to %d rungs, got %d", PREDICT_LADDER_MAX_RUNGS, n);
        return -1;
    }
    for (int k = 0; k < n; k++) {
        if (nodes[k] < 5 || (k > 0 && nodes[k] <= nodes[k - 1])) {
            snprintf(why, why_len, "ladder nodes must be increasing and at least 5 (rung %d: %d)", k + 1, nodes[k]);
            return -1;
        }
    }
    for (int k = 0; k < n; k++) {
        rod_scene s = *sc;
        s.nodes = nodes[k];
        s.dt = predict_ladder_dt(sc->dt, nodes[n - 1], nodes[k]);
        rod_predict_opts o = rod_predict_opts_default();
        o.adaptive = adaptive;
        o.adapt_scale = adaptive ? s.dt / sc->dt : 0.0;
        o.on_sample = stop_if_cancelled;
        o.user = (void *)cancel;
        rod_prediction p;
        char err[256] = "";
        rod_status st = rod_predict(&s, &o, &p, err, sizeof err);
        if (cancel && atomic_load(cancel)) {
            snprintf(why, why_len, "cancelled at ladder rung N = %d", nodes[k]);
            return -1;
        }
        if (st != ROD_OK) {
            snprintf(why, why_len, "ladder rung N = %d: %s", nodes[k], err);
            return -1;
        }
        if (!p.snapped) {
            snprintf(why, why_len, "ladder rung N = %d: no snap up to Delta W = %g, no error to estimate", nodes[k],
                     sc->shear_max);
            return -1;
        }
        predict_ladder_rung *r = &out[k];
        memset(r, 0, sizeof *r);
        r->nodes = nodes[k];
        r->dt = s.dt;
        r->adaptive = adaptive;
        r->adapt_scale = o.adapt_scale;
        r->snapped = 1;
        r->snap_dw = p.snap_dw;
        r->asymmetric = p.asymmetric;
        r->wall_s = p.wall_s;
        r->est_error = -1.0;
        if (progress) progress(user, r, k, n);
    }
    predict_ladder_estimate_errors(out, n, verdict);
    return 0;
}

int predict_ladder_choose(const predict_ladder_rung *r, int n, double target_error)
{
    int best = -1, finest = n - 1;
    for (int k = 0; k < n; k++) {
        if (r[k].est_error >= 0.0 && r[k].est_error <= target_error && (best < 0 || r[k].wall_s < r[best].wall_s))
            best = k;
    }
    return best >= 0 ? best : finest;
}
