/* trial_publish.c: formatting the session's live messages (see trial_publish.h, docs/live-page.md). */
#include "trial_publish.h"

#include <stdio.h>

void trial_publish_begin(live_bus *b, int64_t trial_id, const char *mode, const char *note)
{
    if (!b) return;
    char m[1024], n1[300], n2[32];
    snprintf(m, sizeof m, "{\"type\":\"trial\",\"trial\":%lld,\"mode\":\"%s\",\"note\":\"%s\"}", (long long)trial_id,
             live_str(n2, sizeof n2, mode), live_str(n1, sizeof n1, note));
    live_bus_publish(b, m, 1);
}

void trial_publish_state_name(live_bus *b, int64_t trial_id, const char *state, double t_s, const char *why)
{
    if (!b) return;
    char m[1024], t[32], w[600], n[160]; /* n: "done, refitting specimen NAME" too */
    snprintf(m, sizeof m, "{\"type\":\"state\",\"trial\":%lld,\"state\":\"%s\",\"t\":%s,\"why\":\"%s\"}",
             (long long)trial_id, live_str(n, sizeof n, state), live_num(t, sizeof t, t_s),
             live_str(w, sizeof w, why));
    live_bus_publish(b, m, 0);
}

void trial_publish_state(live_bus *b, int64_t trial_id, trial_state s, double t_s, const char *why)
{
    trial_publish_state_name(b, trial_id, trial_state_name(s), t_s, why);
}

void trial_publish_event(live_bus *b, int64_t trial_id, double t_s, const char *kind, const char *message)
{
    if (!b) return;
    char m[1024], t[32], k[32], w[700];
    snprintf(m, sizeof m, "{\"type\":\"event\",\"trial\":%lld,\"t\":%s,\"kind\":\"%s\",\"message\":\"%s\"}",
             (long long)trial_id, live_num(t, sizeof t, t_s), live_str(k, sizeof k, kind),
             live_str(w, sizeof w, message));
    live_bus_publish(b, m, 0);
}

void trial_publish_sample(live_bus *b, int64_t trial_id, const trial_sample *x)
{
    if (!b) return;
    char m[1024], t[32], dl[32], dw[32], dz[32], a[32], q[32], cm[32], sm[32];
    int measured = x->kind && x->measured;
    snprintf(m, sizeof m,
             "{\"type\":\"sample\",\"trial\":%lld,\"kind\":\"%s\",\"frame\":%ld,\"t\":%s,\"compress_mm\":%s,"
             "\"shear_mm\":%s,\"dl\":%s,\"dw\":%s,\"measured\":%s,\"dz\":%s,\"a\":%s,\"quality\":%s,"
             "\"untracked\":%s}",
             (long long)trial_id, x->kind ? "frame" : "rail", x->kind ? x->frame : -1L, live_num(t, sizeof t, x->t_s),
             live_num(cm, sizeof cm, x->compress_mm), live_num(sm, sizeof sm, x->shear_mm),
             live_num(dl, sizeof dl, x->dl), live_num(dw, sizeof dw, x->dw), measured ? "true" : "false",
             live_num(dz, sizeof dz, measured ? x->dz : 0.0 / 0.0), live_num(a, sizeof a, measured ? x->a : 0.0 / 0.0),
             live_num(q, sizeof q, x->kind ? x->quality : 0.0 / 0.0),
             !x->kind || !x->not_tracked ? "null" : x->not_tracked == 2 ? "\"dropped\"" : "\"skipped\"");
    live_bus_publish(b, m, 0);
}

void trial_publish_frame(live_bus *b, const vis_frame *f, const vis_tracker *trk, long index, double t_s)
{
    if (!b || !f || !live_bus_frame_due(b, t_s)) return;
    static const size_t max = LIVE_UV_MAX;
    double uv[2 * LIVE_UV_MAX];
    trial_publish_frame_curve(b, f, uv, trk ? vis_tracker_curve(trk, uv, max) : 0, index, t_s);
}

void trial_publish_frame_curve(live_bus *b, const vis_frame *f, const double *uv, size_t n, long index, double t_s)
{
    if (!b || !f || !live_bus_frame_due(b, t_s)) return;
    if (n > LIVE_UV_MAX) n = LIVE_UV_MAX;
    live_bus_publish_frame(b, t_s, index, vis_frame_width(f), vis_frame_height(f), vis_frame_channels(f),
                           vis_frame_stride(f), vis_frame_data((vis_frame *)f), uv, n);
}

void trial_publish_prediction(live_bus *b, int64_t trial_id, int ok, int snapped, double snap_dw, const char *regime,
                           size_t n, const double *dw, const double *dz, const double *a, const char *why)
{
    if (!b) return;
    if (ok && n > 0) live_bus_publish_curve(b, trial_id, n, dw, dz, a);
    char m[1024], s[32], r[32], w[700];
    if (ok)
        snprintf(m, sizeof m,
                 "{\"type\":\"prediction\",\"trial\":%lld,\"ok\":true,\"snapped\":%s,\"snap_dw\":%s,\"regime\":\"%s\","
                 "\"points\":%zu}",
                 (long long)trial_id, snapped ? "true" : "false", live_num(s, sizeof s, snapped ? snap_dw : 0.0 / 0.0),
                 live_str(r, sizeof r, regime), n);
    else
        snprintf(m, sizeof m, "{\"type\":\"prediction\",\"trial\":%lld,\"ok\":false,\"why\":\"%s\"}",
                 (long long)trial_id, live_str(w, sizeof w, why));
    live_bus_publish(b, m, 0);
}

void trial_publish_result(live_bus *b, int64_t trial_id, const trial_result *r)
{
    if (!b) return;
    char m[1024], s[32], w[600], reg[32], d[32];
    snprintf(m, sizeof m,
             "{\"type\":\"result\",\"trial\":%lld,\"final\":\"%s\",\"reason\":\"%s\",\"snapped\":%s,\"snap_dw\":%s,"
             "\"regime\":\"%s\",\"frames\":%ld,\"measured_frames\":%ld,\"duration_s\":%s}",
             (long long)trial_id, trial_state_name(r->final), live_str(w, sizeof w, r->reason),
             r->snapped ? "true" : "false", live_num(s, sizeof s, r->snapped ? r->snap_dw : 0.0 / 0.0),
             live_str(reg, sizeof reg, r->regime), r->frames, r->measured_frames,
             live_num(d, sizeof d, r->duration_s));
    live_bus_publish(b, m, 0);
}

void trial_publish_stored(live_bus *b, int64_t trial_id, trial_state final)
{
    if (!b) return;
    char m[160];
    snprintf(m, sizeof m, "{\"type\":\"stored\",\"trial\":%lld,\"final\":\"%s\"}", (long long)trial_id,
             trial_state_name(final));
    live_bus_publish(b, m, 0);
}

void trial_publish_calibrated(live_bus *b, int64_t trial_id, const trial_calibrated *r)
{
    if (!b || !r) return;
    char m[1024], s[32], sd[32], p[32], c[32], t[32], w[700];
    if (r->ok)
        snprintf(m, sizeof m,
                 "{\"type\":\"calibrated\",\"trial\":%lld,\"ok\":true,\"refresh\":%d,\"t\":%s,\"dw_cut\":%s,"
                 "\"snapped\":%s,\"snap_dw\":%s,\"snap_sd\":%s,\"regime\":\"%s\",\"p_other\":%s}",
                 (long long)trial_id, r->refresh, live_num(t, sizeof t, r->t_landed), live_num(c, sizeof c, r->dw_cut),
                 r->snapped ? "true" : "false", live_num(s, sizeof s, r->snapped ? r->snap_dw : 0.0 / 0.0),
                 live_num(sd, sizeof sd, r->snapped ? r->snap_sd : 0.0 / 0.0),
                 !r->snapped ? "no snap" : r->asymmetric ? "asymmetric" : "symmetric",
                 live_num(p, sizeof p, r->snapped ? r->p_other : 0.0 / 0.0));
    else
        snprintf(m, sizeof m,
                 "{\"type\":\"calibrated\",\"trial\":%lld,\"ok\":false,\"refresh\":%d,\"t\":%s,\"reason_key\":\"%s\","
                 "\"why\":\"%s\"}",
                 (long long)trial_id, r->refresh, live_num(t, sizeof t, r->t_landed), r->reason_key,
                 live_str(w, sizeof w, r->reason));
    live_bus_publish(b, m, 0);
}
