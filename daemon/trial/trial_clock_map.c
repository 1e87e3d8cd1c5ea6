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

/* Least-squares line through the block minima (camera time, min difference). */
static void refit(trial_clock_map *m)
{
    int n = m->n_blk;
    if (n < 3) return;
    double cref = m->blk_cam[0];
    for (int k = 1; k < n; k++) cref = fmin(cref, m->blk_cam[k]);
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int k = 0; k < n; k++) {
        double x = m->blk_cam[k] - cref, y = m->blk_min[k];
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
    }
    double span = 0.0;
    for (int k = 0; k < n; k++) span = fmax(span, m->blk_cam[k] - cref);
    if (span < TRIAL_CLOCK_MIN_DRIFT_SPAN_S) {
        /* Too short a baseline for a slope (the minima's scatter over it would be read as drift):
         * the lowest block minimum. */
        double lo = m->blk_min[0];
        for (int k = 1; k < n; k++) lo = fmin(lo, m->blk_min[k]);
        m->a = lo;
        m->b = 0.0;
        m->cam_ref = cref;
        m->fitted = 1;
        return;
    }
    double den = n * sxx - sx * sx;
    if (!(den > 0.0)) return;
    m->b = (n * sxy - sx * sy) / den;
    m->a = (sy - m->b * sx) / n;
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
