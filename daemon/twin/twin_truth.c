/* twin_truth.c: the twin's truth as text (see twin_truth.h). */
#include "twin_truth.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void twin_truth_params(const rod_scene *sc, const char *const *keys, int n, char *buf, size_t len)
{
    if (!buf || !len) return;
    int used = snprintf(buf, len, TWIN_PARAMS_PREFIX "N = %d, dt = %g s; ", sc->nodes, sc->dt);
    if (used < 0 || (size_t)used >= len) return;
    if (n <= 0 || !keys) {
        snprintf(buf + used, len - (size_t)used, "the trial's scene (no [twin])");
        return;
    }
    int k = snprintf(buf + used, len - (size_t)used, "[twin]");
    for (int i = 0; i < n && k >= 0 && (size_t)(used + k) < len; i++) {
        used += k;
        k = snprintf(buf + used, len - (size_t)used, " %s", keys[i] ? keys[i] : "");
    }
}

void twin_truth_snap(const rod_snap_report *r, double rate, double dw_now, char *buf, size_t len)
{
    if (!buf || !len) return;
    if (!r->snapped) {
        snprintf(buf, len, TWIN_TRUTH_PREFIX "no snap (Delta W reached %.5f)", isfinite(dw_now) ? dw_now : 0.0);
        return;
    }
    char follow[64] = "";
    if (!r->final) snprintf(follow, sizeof follow, "; the pathway followed for less than 2 s");
    snprintf(buf, len,
             TWIN_TRUTH_PREFIX "snap Delta W = %.5f, regime %s (peak |A| %.3f rad over the passage, %.3f over 2 s, "
             "camera's A %.3f; the onset known to %.5f of Delta W%s)",
             r->snap_dw, rod_snap_report_regime(r), r->peak_abs_a, r->peak_abs_a_post, r->peak_abs_a_cam,
             r->dt_max * rate, follow);
}

int twin_truth_parse(const char *msg, double *snap_dw, char *regime, size_t regime_len)
{
    if (!msg) return 0;
    const char *p = strstr(msg, TWIN_TRUTH_PREFIX);
    if (!p) return 0;
    p += strlen(TWIN_TRUTH_PREFIX);
    if (!strncmp(p, "no snap", 7)) {
        if (regime && regime_len) snprintf(regime, regime_len, "no snap");
        return 0;
    }
    double dw;
    char reg[16];
    if (sscanf(p, "snap Delta W = %lf, regime %15[a-z]", &dw, reg) != 2 || !isfinite(dw)) return 0;
    if (strcmp(reg, "asymmetric") && strcmp(reg, "symmetric")) return 0;
    if (snap_dw) *snap_dw = dw;
    if (regime && regime_len) snprintf(regime, regime_len, "%s", reg);
    return 1;
}
