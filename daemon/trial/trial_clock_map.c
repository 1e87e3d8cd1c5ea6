/* trial_clock_map.c: camera clock -> host monotonic clock by the arrivals' lower envelope
 * (see trial_clock_map.h). */
#include "trial_clock_map.h"

#include <math.h>
#include <string.h>

void trial_clock_map_init(trial_clock_map *m)
{
    memset(m, 0, sizeof *m);
    m->all_min = INFINITY;
    m->cur_min = INFINITY;
}

/* The lower envelope's line through the block minima (camera time, min difference). Its slope
 * joins the lowest minimum of the window's first third to the lowest of its last third (two
 * points at least a third of the window apart, each near the transport floor); its offset puts
 * the line through the lowest point of the last third, so the line is at the floor where it is
 * used (the newest frames) and extrapolates over at most a third of the window. A least-squares
 * line through the minima would sit at their mean, above the floor by the typical block's excess
 * (0.7 ms measured on a loaded 2-core machine, where 1 frame in 150 arrives at the floor). */
static void refit(trial_clock_map *m)
{
    int n = m->n_blk;
    if (n < 3) return;
    /* the minima in camera-time order: the ring's oldest first */
    double x[TRIAL_CLOCK_BLOCKS], y[TRIAL_CLOCK_BLOCKS];
    int first = n < TRIAL_CLOCK_BLOCKS ? 0 : m->next_blk;
    for (int k = 0; k < n; k++) {
        x[k] = m->blk_cam[(first + k) % TRIAL_CLOCK_BLOCKS];
        y[k] = m->blk_min[(first + k) % TRIAL_CLOCK_BLOCKS];
    }
    const double cref = x[n - 1];
    double b = 0.0;
    int third = n / 3;
    int sloped = x[n - 1] - x[0] >= TRIAL_CLOCK_MIN_DRIFT_SPAN_S && third >= 1;
    if (sloped) {
        int i1 = 0, i3 = n - third;
        for (int k = 1; k < third; k++)
            if (y[k] < y[i1]) i1 = k;
        for (int k = n - third + 1; k < n; k++)
            if (y[k] < y[i3]) i3 = k;
        if (x[i3] > x[i1]) b = (y[i3] - y[i1]) / (x[i3] - x[i1]);
        if (b > TRIAL_CLOCK_MAX_DRIFT) b = TRIAL_CLOCK_MAX_DRIFT;
        if (b < -TRIAL_CLOCK_MAX_DRIFT) b = -TRIAL_CLOCK_MAX_DRIFT;
    }
    /* Before the drift's baseline (b = 0): the lowest minimum of the whole window. */
    int from = sloped ? n - third : 0;
    double a = INFINITY;
    for (int k = from; k < n; k++) a = fmin(a, y[k] - b * (x[k] - cref));
    m->a = a;
    m->b = b;
    m->cam_ref = cref;
    m->fitted = 1;
}

double trial_clock_map_offset(const trial_clock_map *m, double camera_t_s)
{
    if (m->identity || !m->started) return 0.0;
    if (m->fitted) return m->a + m->b * (camera_t_s - m->cam_ref);
    /* Before the fit: the smallest difference seen so far, and the open block's if smaller. */
    return fmin(m->all_min, m->cur_min);
}

double trial_clock_map_drift(const trial_clock_map *m) { return m->fitted ? m->b : 0.0; }

double trial_clock_map_add(trial_clock_map *m, double camera_t_s, double host_t_s)
{
    if (!isfinite(camera_t_s)) return host_t_s;
    double d = host_t_s - camera_t_s;
    if (!m->started) {
        m->started = 1;
        m->identity = d >= 0.0 && d < 1.0;
    }
    m->n++;
    if (m->identity) return camera_t_s;
    if (d < m->cur_min) {
        m->cur_min = d;
        m->cur_cam = camera_t_s;
    }
    if (d < m->all_min) m->all_min = d;
    if (++m->cur_n >= TRIAL_CLOCK_BLOCK) {
        m->blk_min[m->next_blk] = m->cur_min;
        m->blk_cam[m->next_blk] = m->cur_cam;
        m->next_blk = (m->next_blk + 1) % TRIAL_CLOCK_BLOCKS;
        if (m->n_blk < TRIAL_CLOCK_BLOCKS) m->n_blk++;
        m->cur_n = 0;
        m->cur_min = INFINITY;
        refit(m);
    }
    double off = trial_clock_map_offset(m, camera_t_s);
    /* The mapping never puts a frame after its own arrival. */
    return fmin(camera_t_s + off, host_t_s);
}
