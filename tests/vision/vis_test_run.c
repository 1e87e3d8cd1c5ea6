/* vis_test_run.c: see vis_test_run.h. */
#define _XOPEN_SOURCE 700 /* nftw */
#include "vis_test_run.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <ftw.h>
#include <unistd.h>

static char tmp_dir[512];

static int rm_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb;
    (void)flag;
    (void)ftw;
    return remove(path);
}

/* Remove the temporary directory at exit, unless VT_KEEP is set (to look at the videos). */
static void tmp_cleanup(void)
{
    if (tmp_dir[0] && strcmp(tmp_dir, "/tmp") != 0 && !getenv("VT_KEEP"))
        nftw(tmp_dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
}

const char *vt_tmpdir(void)
{
    char *dir = tmp_dir;
    if (!dir[0]) {
        const char *base = getenv("TMPDIR");
        snprintf(dir, sizeof tmp_dir, "%s/vistestXXXXXX", base && base[0] ? base : "/tmp");
        if (!mkdtemp(dir)) {
            perror("mkdtemp");
            snprintf(dir, sizeof tmp_dir, "/tmp");
        } else {
            atexit(tmp_cleanup);
        }
    }
    return dir;
}

int vt_run(const char *name, vt_gen_fn gen, void *ctx, int frames, const vis_render_params *p,
           const vis_calib *c, const vis_track_params *tp, vt_result *r)
{
    static vt_shape sh;
    vis_render_truth truth[VT_MAXF];
    char video[600], csv[600];
    vis_error err;
    memset(r, 0, sizeof *r);
    if (frames > VT_MAXF)
        frames = VT_MAXF;
    snprintf(video, sizeof video, "%s/%s.mkv", vt_tmpdir(), name);
    snprintf(csv, sizeof csv, "%s/%s.csv", vt_tmpdir(), name);
    vis_synth_writer *w = vis_synth_writer_open(video, csv, p, 25.0, &err);
    if (!w) {
        printf("%s: %s\n", name, err.message);
        return -1;
    }
    for (int i = 0; i < frames; i++) {
        gen(&sh, i, ctx);
        if (vis_synth_writer_add(w, &sh.view, &truth[i], &err) != VIS_OK) {
            printf("%s: frame %d: %s\n", name, i, err.message);
            vis_synth_writer_close(w, NULL);
            return -1;
        }
    }
    if (vis_synth_writer_close(w, &err) != VIS_OK) {
        printf("%s: %s\n", name, err.message);
        return -1;
    }
    r->frames = frames;
    vis_source *src = vis_source_open_video(video, &err);
    vis_tracker *t = vis_tracker_create(tp, c, &err);
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    if (!src || !t || !f) {
        printf("%s: %s\n", name, err.message);
        vis_source_close(src);
        vis_tracker_free(t);
        vis_frame_free(f);
        return -1;
    }
    double sdz = 0, sa = 0;
    int rc = 0;
    for (int i = 0; i < frames; i++) {
        double ts;
        if (vis_source_read(src, f, &ts, &err) != VIS_OK) {
            printf("%s: read frame %d: %s\n", name, i, err.message);
            rc = -1;
            break;
        }
        vis_measure m;
        const vis_truth *g = &truth[i].truth;
        if (vis_tracker_process(t, f, g->shear_m * 1000.0, &m, &err) != VIS_OK) {
            printf("%s: track frame %d: %s\n", name, i, err.message);
            rc = -1;
            break;
        }
        r->reason[i] = m.reason;
        r->quality[i] = m.quality;
        if (m.reason != VIS_REASON_NONE) {
            printf("%s: frame %d not measured: %s (quality %.3f)\n", name, i, vis_reason_str(m.reason),
                   m.quality);
            continue;
        }
        r->measured++;
        r->valid[i] = 1;
        r->dz[i] = m.dz;
        /* Heights compared in metres, then in pixels of the y = 0 plane: the tracker normalises by
         * the l it is given, the truth by the shape's own 3D length. */
        const double edz = (m.dz * tp->length_mm * 1e-3 - g->dz_cam * g->length_m) * truth[i].px_per_m;
        const double ea = m.a - g->a_cam;
        sdz += edz * edz;
        sa += ea * ea;
        r->dz_max_px = fmax(r->dz_max_px, fabs(edz));
        r->a_max = fmax(r->a_max, fabs(ea));
        if (getenv("VT_VERBOSE"))
            printf("%s %2d: dz %.5f (true %.5f, %+.3f px) a %+.4f (true %+.4f) q %.3f res %.3f px\n",
                   name, i, m.dz, g->dz_cam, edz, m.a, g->a_cam, m.quality, m.residual_px);
    }
    if (r->measured) {
        r->dz_rms_px = sqrt(sdz / r->measured);
        r->a_rms = sqrt(sa / r->measured);
    }
    printf("%s: %d/%d frames measured, Delta Z error %.3f px RMS (max %.3f), A error %.4f rad RMS "
           "(max %.4f)\n",
           name, r->measured, r->frames, r->dz_rms_px, r->dz_max_px, r->a_rms, r->a_max);
    vis_source_close(src);
    vis_tracker_free(t);
    vis_frame_free(f);
    return rc;
}
