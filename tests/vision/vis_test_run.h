/* vis_test_run.h: render a sequence into an FFV1 video with ground truth, read it back, track it,
 * and score the tracker against the projected ground truth (shared by the vision tests). */
#ifndef VIS_TEST_RUN_H
#define VIS_TEST_RUN_H

#include "vis_test_shapes.h"

#define VT_MAXF 64

/* Fills `s` for frame `i` of a sequence. */
typedef void (*vt_gen_fn)(vt_shape *s, int i, void *ctx);

typedef struct vt_result {
    int frames;                 /* frames rendered */
    int measured;               /* frames with reason NONE */
    double dz_rms_px;           /* RMS of (dz - dz_cam) * l * px_per_m, pixels */
    double a_rms;               /* RMS of (a - a_cam), radians */
    double dz_max_px, a_max;    /* worst frame */
    double dz[VT_MAXF];         /* measured Delta Z per frame */
    unsigned char valid[VT_MAXF];
    vis_reason reason[VT_MAXF];
    double quality[VT_MAXF];
} vt_result;

/* Temporary directory for this test process (created once, under TMPDIR or /tmp, removed at exit
 * unless VT_KEEP is set). */
const char *vt_tmpdir(void);
/* Render `frames` frames with `p`, write NAME.mkv + NAME.csv in the temp dir, track with `tp` and
 * `c`, fill `r`. Returns 0 on success; on failure prints why and returns -1. */
int vt_run(const char *name, vt_gen_fn gen, void *ctx, int frames, const vis_render_params *p,
           const vis_calib *c, const vis_track_params *tp, vt_result *r);

#endif
