/* twin_frames.c: the frame clock (twin_frames.h). The previous and current states swap roles by
 * swapping the two shape structs, so a push copies the rod once and nothing else. */
#include "twin_frames.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A frame is due when its time is within this fraction of a frame period of the state's time, so
 * that round-off in accumulated step times does not push a frame to the next step. */
#define TWIN_FRAME_EPS 1e-9

twin_status twin_frames_init(twin_frames *f, const rod_scene *sc, twin_y_origin y, double fps,
                             twin_frame_fn fn, void *user, char *why, size_t why_len)
{
    if (!f || !sc || !fn) {
        if (why && why_len) snprintf(why, why_len, "twin_frames_init: NULL clock, scene or callback");
        return TWIN_ERR_ARG;
    }
    memset(f, 0, sizeof *f);
    if (!(isfinite(fps) && fps > 0 && fps <= 10000)) {
        if (why && why_len) snprintf(why, why_len, "twin_frames_init: fps must be in (0, 10000], got %g", fps);
        return TWIN_ERR_ARG;
    }
    twin_status st = twin_shape_init(&f->a, sc, y, why, why_len);
    if (st == TWIN_OK) st = twin_shape_init(&f->b, sc, y, why, why_len);
    if (st == TWIN_OK) st = twin_shape_init(&f->mix, sc, y, why, why_len);
    if (st != TWIN_OK) {
        twin_frames_release(f);
        return st;
    }
    f->fps = fps;
    f->fn = fn;
    f->user = user;
    return TWIN_OK;
}

void twin_frames_release(twin_frames *f)
{
    if (!f) return;
    twin_shape_release(&f->a);
    twin_shape_release(&f->b);
    twin_shape_release(&f->mix);
}

twin_status twin_frames_push(twin_frames *f, double t_s, const rod *r, char *why, size_t why_len)
{
    if (!f || !r || !f->fn || !f->a.pos) {
        if (why && why_len) snprintf(why, why_len, "twin_frames_push: NULL or released clock");
        return TWIN_ERR_ARG;
    }
    if (!isfinite(t_s) || (f->have_prev && t_s < f->t_prev)) {
        if (why && why_len) snprintf(why, why_len, "twin_frames_push: time %g s is not finite or goes back", t_s);
        return TWIN_ERR_ARG;
    }
    twin_status st = twin_shape_from_rod(&f->b, r, why, why_len);
    if (st != TWIN_OK) return st;
    for (;;) {
        const double tk = f->next / f->fps;
        if (tk > t_s + TWIN_FRAME_EPS / f->fps) break;
        const twin_shape *shape = &f->b;
        if (f->have_prev && t_s > f->t_prev) {
            const double w = fmin(1.0, fmax(0.0, (tk - f->t_prev) / (t_s - f->t_prev)));
            st = twin_shape_lerp(&f->mix, &f->a, &f->b, w, why, why_len);
            if (st != TWIN_OK) return st;
            shape = &f->mix;
        }
        const int idx = f->next++;
        if (f->fn(f->user, idx, tk, &shape->view)) {
            if (why && why_len) snprintf(why, why_len, "stopped by the frame callback at frame %d", idx);
            return TWIN_STOPPED;
        }
    }
    twin_shape tmp = f->a;
    f->a = f->b;
    f->b = tmp;
    f->t_prev = t_s;
    f->have_prev = 1;
    return TWIN_OK;
}
