/* trial_latency.c: the snap-to-stop breakdown of a live trial (see trial_latency.h). */
#include "trial_latency.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

void trial_latency_init(trial_latency *l, double t0_mono)
{
    l->t0_mono = t0_mono;
    l->onset_frame = l->det_frame = -1;
    l->t_onset = l->t_det = l->t_det_arrival = l->t_picked = l->t_tracked = l->cpu_tracked = l->t_decided = l->t_stop_ret = l->t_stand = NAN;
}

double trial_latency_thread_cpu_s(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) return NAN;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double trial_latency_watch_window_s(double v_mm_s, double a_mm_s2)
{
    double decel = (isfinite(v_mm_s) && isfinite(a_mm_s2) && a_mm_s2 > 0.0) ? fabs(v_mm_s) / a_mm_s2 : 0.0;
    return fmin(decel, 5.0) + 0.5;
}

/* " TEXT X ms" or " TEXT n/a" for the span a -> b. */
static size_t span(char *out, size_t len, size_t n, const char *text, double a, double b)
{
    if (n >= len) return n;
    int k = (isfinite(a) && isfinite(b)) ? snprintf(out + n, len - n, "%s %.1f ms", text, 1e3 * (b - a))
                                         : snprintf(out + n, len - n, "%s n/a", text);
    return k > 0 ? n + (size_t)k : n;
}

const char *trial_latency_format(const trial_latency *l, char *msg, size_t len)
{
    if (!len) return msg;
    msg[0] = '\0';
    size_t n = 0;
    int k = snprintf(msg, len, "snap-to-stop breakdown: onset frame %ld -> detection frame %ld (at %.4f s)",
                     l->onset_frame, l->det_frame, l->t_det);
    n = k > 0 ? (size_t)k : 0;
    n = span(msg, len, n, "", l->t_onset, l->t_det);
    /* Arrival is optional (a paced mock camera has none): the decision then counts from the frame. */
    double from = isfinite(l->t_det_arrival) ? l->t_det_arrival : l->t_det;
    n = span(msg, len, n, "; frame -> arrival", l->t_det, l->t_det_arrival);
    n = span(msg, len, n, " -> picked up", from, l->t_picked);
    n = span(msg, len, n, " -> tracked", isfinite(l->t_picked) ? l->t_picked : from, l->t_tracked);
    if (isfinite(l->cpu_tracked) && n < len) {
        int c = snprintf(msg + n, len - n, " (CPU %.1f ms)", 1e3 * l->cpu_tracked);
        n = c > 0 ? n + (size_t)c : n;
    }
    n = span(msg, len, n, " -> decided", isfinite(l->t_tracked) ? l->t_tracked : isfinite(l->t_picked) ? l->t_picked : from,
             l->t_decided);
    n = span(msg, len, n, " -> stop returned", l->t_decided, l->t_stop_ret);
    n = span(msg, len, n, " -> read standing", l->t_stop_ret, l->t_stand);
    n = span(msg, len, n, "; total", l->t_det, l->t_stand);
    if (n < len) snprintf(msg + n, len - n, "; t0_mono %.6f", l->t0_mono);
    return msg;
}
