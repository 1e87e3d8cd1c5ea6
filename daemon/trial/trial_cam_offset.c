/* trial_cam_offset.c: the camera's time offset from the shear's start (see trial_cam_offset.h). */
#include "trial_cam_offset.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CAM_OFFSET_MIN_STANDING 10 /* frames before the ramp */
#define CAM_OFFSET_MIN_CRUISE 20   /* frames after it */
#define CAM_OFFSET_MIN_READINGS 4  /* cruise readings of the rail */
#define CAM_OFFSET_LAST_FRAMES 10  /* frames whose mean gives the direction of motion */
#define CAM_OFFSET_CURV_STEPS 5    /* grid steps either side for the parabola at the minimum */

struct trial_cam_offset {
    size_t cap_f, cap_r, nf, nr;
    double *ft, *fp; /* frames: time, and 4 coordinates each (left u v, right u v) */
    double *rt, *rs; /* readings */
    double *q;       /* scratch: each frame's coordinate along the motion */
    double *x;       /* scratch: the rail travel at each frame's shown time */
    unsigned char *use;
};

trial_cam_offset_params trial_cam_offset_params_default(void)
{
    return (trial_cam_offset_params){.search_s = 0.1, .step_s = 2e-4, .ramp_s = 0.25, .min_motion_px = 1.0};
}

trial_cam_offset *trial_cam_offset_alloc(size_t max_frames, size_t max_readings)
{
    trial_cam_offset *o = calloc(1, sizeof *o);
    if (!o) return NULL;
    o->cap_f = max_frames;
    o->cap_r = max_readings;
    o->ft = malloc((max_frames + 1) * sizeof *o->ft);
    o->fp = malloc((max_frames + 1) * 4 * sizeof *o->fp);
    o->q = malloc((max_frames + 1) * sizeof *o->q);
    o->x = malloc((max_frames + 1) * sizeof *o->x);
    o->use = malloc(max_frames + 1);
    o->rt = malloc((max_readings + 1) * sizeof *o->rt);
    o->rs = malloc((max_readings + 1) * sizeof *o->rs);
    if (!o->ft || !o->fp || !o->q || !o->x || !o->use || !o->rt || !o->rs) {
        trial_cam_offset_free(o);
        return NULL;
    }
    return o;
}

void trial_cam_offset_free(trial_cam_offset *o)
{
    if (!o) return;
    free(o->ft);
    free(o->fp);
    free(o->q);
    free(o->x);
    free(o->use);
    free(o->rt);
    free(o->rs);
    free(o);
}

void trial_cam_offset_clear(trial_cam_offset *o) { o->nf = o->nr = 0; }

void trial_cam_offset_add_frame(trial_cam_offset *o, double t_s, const double left_px[2], const double right_px[2])
{
    if (o->nf >= o->cap_f || !isfinite(t_s)) return;
    double *p = o->fp + 4 * o->nf;
    p[0] = left_px[0];
    p[1] = left_px[1];
    p[2] = right_px[0];
    p[3] = right_px[1];
    if (!(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]) && isfinite(p[3]))) return;
    o->ft[o->nf++] = t_s;
}

void trial_cam_offset_add_reading(trial_cam_offset *o, double t_s, double shear_mm)
{
    if (o->nr >= o->cap_r || !isfinite(t_s) || !isfinite(shear_mm)) return;
    o->rt[o->nr] = t_s;
    o->rs[o->nr++] = shear_mm;
}

size_t trial_cam_offset_frames(const trial_cam_offset *o) { return o->nf; }

/* The rail's standing position, cruise speed and virtual start from its readings. */
static int rail_path(const trial_cam_offset *o, double t_cmd, double ramp_s, double *s0, double *v, double *t_r,
                     int *n_cruise, char *why, size_t why_len)
{
    double sum = 0.0;
    int n0 = 0;
    for (size_t i = 0; i < o->nr; i++)
        if (o->rt[i] <= t_cmd) {
            sum += o->rs[i];
            n0++;
        }
    if (n0 == 0) {
        snprintf(why, why_len, "no reading of the shear rail standing before the shear");
        return -1;
    }
    *s0 = sum / n0;
    double t_move = NAN;
    for (size_t i = 0; i < o->nr; i++)
        if (o->rt[i] > t_cmd && fabs(o->rs[i] - *s0) > 1e-3) {
            t_move = o->rt[i];
            break;
        }
    if (!isfinite(t_move)) {
        snprintf(why, why_len, "the shear rail's readings never left %.3f mm", *s0);
        return -1;
    }
    /* Least squares line s = s_mean + v (t - t_mean) through the cruise readings. */
    double st = 0.0, ss = 0.0;
    int n = 0;
    for (size_t i = 0; i < o->nr; i++)
        if (o->rt[i] >= t_move + ramp_s) {
            st += o->rt[i];
            ss += o->rs[i];
            n++;
        }
    if (n < CAM_OFFSET_MIN_READINGS) {
        snprintf(why, why_len, "%d readings of the shear rail at its cruise speed (at least %d)", n,
                 CAM_OFFSET_MIN_READINGS);
        return -1;
    }
    double tm = st / n, sm = ss / n, stt = 0.0, sts = 0.0;
    for (size_t i = 0; i < o->nr; i++)
        if (o->rt[i] >= t_move + ramp_s) {
            stt += (o->rt[i] - tm) * (o->rt[i] - tm);
            sts += (o->rt[i] - tm) * (o->rs[i] - sm);
        }
    if (!(stt > 0.0) || !(fabs(sts / stt) > 1e-6)) {
        snprintf(why, why_len, "the shear rail did not move steadily after its start");
        return -1;
    }
    *v = sts / stt;
    *t_r = tm - (sm - *s0) / *v;
    *n_cruise = n;
    return 0;
}

/* Least squares q = a + b x + c x^2 over the frames in use; the residual sum of squares. */
static double fit_sse(const trial_cam_offset *o)
{
    double m[3][4] = {{0}};
    for (size_t j = 0; j < o->nf; j++) {
        if (!o->use[j]) continue;
        const double x = o->x[j], f[3] = {1.0, x, x * x};
        for (int r = 0; r < 3; r++) {
            for (int k = 0; k < 3; k++) m[r][k] += f[r] * f[k];
            m[r][3] += f[r] * o->q[j];
        }
    }
    /* Gaussian elimination with partial pivoting (3 x 3). */
    for (int col = 0; col < 3; col++) {
        int piv = col;
        for (int r = col + 1; r < 3; r++)
            if (fabs(m[r][col]) > fabs(m[piv][col])) piv = r;
        if (!(fabs(m[piv][col]) > 1e-300)) return NAN;
        for (int k = 0; k < 4; k++) {
            double t = m[col][k];
            m[col][k] = m[piv][k];
            m[piv][k] = t;
        }
        for (int r = col + 1; r < 3; r++) {
            double f = m[r][col] / m[col][col];
            for (int k = col; k < 4; k++) m[r][k] -= f * m[col][k];
        }
    }
    double beta[3];
    for (int r = 2; r >= 0; r--) {
        double s = m[r][3];
        for (int k = r + 1; k < 3; k++) s -= m[r][k] * beta[k];
        beta[r] = s / m[r][r];
    }
    double sse = 0.0;
    for (size_t j = 0; j < o->nf; j++) {
        if (!o->use[j]) continue;
        const double x = o->x[j], e = o->q[j] - (beta[0] + beta[1] * x + beta[2] * x * x);
        sse += e * e;
    }
    return sse;
}

static double sse_at(const trial_cam_offset *o, double tau, double v, double t_r)
{
    trial_cam_offset *w = (trial_cam_offset *)o; /* the scratch arrays only */
    for (size_t j = 0; j < o->nf; j++) w->x[j] = fmax(0.0, v * (o->ft[j] + tau - t_r));
    return fit_sse(o);
}

int trial_cam_offset_estimate(const trial_cam_offset *o, double t_cmd_s, const trial_cam_offset_params *pp,
                              trial_cam_offset_fit *out, char *why, size_t why_len)
{
    trial_cam_offset_params p = pp ? *pp : trial_cam_offset_params_default();
    memset(out, 0, sizeof *out);
    out->offset_s = out->sd_s = NAN;
    if (!(p.search_s > 0.0) || !(p.step_s > 0.0) || p.search_s / p.step_s > 1e5 || !(p.ramp_s >= 0.0)) {
        snprintf(why, why_len, "camera offset: bad search parameters");
        return -1;
    }
    double s0, v, t_r;
    int n_cruise;
    char w[200];
    if (rail_path(o, t_cmd_s, p.ramp_s, &s0, &v, &t_r, &n_cruise, w, sizeof w)) {
        snprintf(why, why_len, "camera offset not measured: %s", w);
        return -1;
    }
    trial_cam_offset *s = (trial_cam_offset *)o; /* scratch */
    /* Standing frames end, and cruise frames begin, where no offset in the search puts the ramp. */
    const double pre = t_r - p.search_s - 0.5 * p.ramp_s, post = t_r + p.search_s + 0.5 * p.ramp_s;
    int n_stand = 0, n_cruise_f = 0;
    double hold[4] = {0}, last[4] = {0};
    for (size_t j = 0; j < o->nf; j++) {
        s->use[j] = o->ft[j] < pre || o->ft[j] > post;
        if (o->ft[j] < pre) {
            n_stand++;
            for (int k = 0; k < 4; k++) hold[k] += o->fp[4 * j + k];
        } else if (o->ft[j] > post)
            n_cruise_f++;
    }
    if (n_stand < CAM_OFFSET_MIN_STANDING || n_cruise_f < CAM_OFFSET_MIN_CRUISE) {
        snprintf(why, why_len,
                 "camera offset not measured: %d frames of the clamp standing and %d moving (at least %d and %d)",
                 n_stand, n_cruise_f, CAM_OFFSET_MIN_STANDING, CAM_OFFSET_MIN_CRUISE);
        return -1;
    }
    int n_last = 0;
    for (size_t j = o->nf; j-- > 0 && n_last < CAM_OFFSET_LAST_FRAMES;)
        if (o->ft[j] > post) {
            for (int k = 0; k < 4; k++) last[k] += o->fp[4 * j + k];
            n_last++;
        }
    for (int k = 0; k < 4; k++) {
        hold[k] /= n_stand;
        last[k] /= n_last;
    }
    /* The shear clamp is the one that moved (left or right in the image, as the camera looks). */
    const double ml = hypot(last[0] - hold[0], last[1] - hold[1]), mr = hypot(last[2] - hold[2], last[3] - hold[3]);
    const int k0 = mr >= ml ? 2 : 0;
    const double motion = fmax(ml, mr);
    if (!(motion >= p.min_motion_px)) {
        snprintf(why, why_len,
                 "camera offset not measured: the shear clamp moved %.2f px in the image (at least %.2f): the camera "
                 "cannot see the shear's start",
                 motion, p.min_motion_px);
        return -1;
    }
    const double e[2] = {(last[k0] - hold[k0]) / motion, (last[k0 + 1] - hold[k0 + 1]) / motion};
    for (size_t j = 0; j < o->nf; j++)
        s->q[j] = (o->fp[4 * j + k0] - hold[k0]) * e[0] + (o->fp[4 * j + k0 + 1] - hold[k0 + 1]) * e[1];
    /* The grid, its minimum, the parabola through its neighbours CAM_OFFSET_CURV_STEPS away. */
    const long n_grid = (long)floor(p.search_s / p.step_s);
    long best = 0;
    double best_sse = INFINITY;
    for (long i = -n_grid; i <= n_grid; i++) {
        double sse = sse_at(o, (double)i * p.step_s, v, t_r);
        if (sse < best_sse) {
            best_sse = sse;
            best = i;
        }
    }
    if (!isfinite(best_sse)) {
        snprintf(why, why_len, "camera offset not measured: the fit is singular");
        return -1;
    }
    const long h = CAM_OFFSET_CURV_STEPS;
    if (labs(best) + h > n_grid) {
        snprintf(why, why_len,
                 "camera offset not measured: the best offset (%.1f ms) is at the edge of the search (+-%.0f ms)",
                 1e3 * (double)best * p.step_s, 1e3 * p.search_s);
        return -1;
    }
    const double d = (double)h * p.step_s, tb = (double)best * p.step_s;
    const double sm = sse_at(o, tb - d, v, t_r), s0c = sse_at(o, tb, v, t_r), sp = sse_at(o, tb + d, v, t_r);
    const double curv = (sp - 2.0 * s0c + sm) / (d * d); /* S'' */
    if (!(curv > 0.0)) {
        snprintf(why, why_len, "camera offset not measured: the fit has no minimum in the offset");
        return -1;
    }
    double tau = tb - (sp - sm) / (2.0 * d) / curv;
    const int n = n_stand + n_cruise_f;
    const double sse = sse_at(o, tau, v, t_r), sigma2 = sse / (double)(n - 4);
    out->offset_s = tau;
    out->sd_s = sqrt(2.0 * sigma2 / curv);
    out->rms_px = sqrt(sse / n);
    out->motion_px = motion;
    out->speed_mm_s = v;
    out->t_start_s = t_r;
    out->frames_used = n;
    out->readings_used = n_cruise;
    return 0;
}
