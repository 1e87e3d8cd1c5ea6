/* twin_frames.h: a camera's fixed frame clock over a simulation's irregular time steps.
 *
 * The simulator accepts steps at its own pace (fast mode grows them up to 100 dt while the ribbon
 * creeps and returns to dt for the snap); a camera takes frames at k / fps. The clock is fed the
 * state after every accepted step (twin_frames_push, e.g. from rod_predict's on_sample callback)
 * and hands out one shape per frame time it has passed: frame k at t_k = k / fps gets the positions
 * interpolated linearly between the two steps around t_k (normals renormalised), an error of
 * order h^2 |x''| / 8 for a step h, far below a pixel during the quasi-static creep (where steps
 * are long but the ribbon barely moves) and during the snap (where steps are dt). Frames before
 * the first pushed state take that state as is: push the state at t = 0 first when it is known
 * (rod_predict reports steps only, so `ribbonctl render` starts from the state after the first
 * step, dt later: a held frame, documented there).
 *
 * Owns three shapes sized once (previous step, current step, interpolated frame): no allocation
 * after twin_frames_init. */
#ifndef RIBBON_DAEMON_TWIN_FRAMES_H
#define RIBBON_DAEMON_TWIN_FRAMES_H

#include "twin_shape.h"

/* Called once per frame, in order from index 0, with the shape at t_s = index / fps (valid during
 * the call only). Return 0 to go on, non-zero to stop (twin_frames_push returns TWIN_STOPPED). */
typedef int (*twin_frame_fn)(void *user, int index, double t_s, const vis_shape *shape);

typedef struct twin_frames {
    double fps;            /* frames per second of simulated time */
    int next;              /* index of the next frame to hand out */
    int have_prev;         /* 1 once a state has been pushed */
    double t_prev;         /* s, time of the previous state */
    twin_shape a, b, mix;  /* previous state, current state, the frame being handed out */
    twin_frame_fn fn;
    void *user;
} twin_frames;

/* Sizes the clock's shapes for the scene; fps in (0, 10000]. On failure nothing needs releasing. */
twin_status twin_frames_init(twin_frames *f, const rod_scene *sc, twin_y_origin y, double fps,
                             twin_frame_fn fn, void *user, char *why, size_t why_len);
void twin_frames_release(twin_frames *f);

/* The rod's state at simulated time t_s (non-decreasing from push to push): hands out every frame
 * with t_k <= t_s not handed out yet. TWIN_STOPPED when the callback asked to stop. */
twin_status twin_frames_push(twin_frames *f, double t_s, const rod *r, char *why, size_t why_len);

/* Frames handed out so far. */
static inline int twin_frames_count(const twin_frames *f) { return f->next; }

#endif
