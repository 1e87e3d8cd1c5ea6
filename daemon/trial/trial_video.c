/* trial_video.c: cropped lossless video of a trial (see trial_video.h). */
#include "trial_video.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/statvfs.h>

struct trial_video {
    vis_video_writer *w;
    vis_frame *crop;
    trial_roi roi;
    long frames;
    char path[1024];
    char dir[1024];    /* the file system the video is on */
    double min_free_bytes; /* to stay free beyond what the next frame may need */
};

/* Bytes a frame may cost on disk at worst, with room for the encoder's buffer and the trailer:
 * the raw size twice over (FFV1 never doubles an image) plus 1 MiB. */
static double frame_need_bytes(const trial_video *v)
{
    return 2.0 * (double)v->roi.w * (double)v->roi.h + 1048576.0;
}

trial_roi trial_roi_clip(trial_roi r, int width, int height)
{
    if (r.x < 0) { r.w += r.x; r.x = 0; }
    if (r.y < 0) { r.h += r.y; r.y = 0; }
    if (r.x + r.w > width) r.w = width - r.x;
    if (r.y + r.h > height) r.h = height - r.y;
    /* FFV1 takes any size; keep even sizes for players that want them. */
    r.w &= ~1;
    r.h &= ~1;
    if (r.w < 16 || r.h < 16) {
        trial_roi full = {0, 0, width & ~1, height & ~1};
        return full;
    }
    return r;
}

trial_roi trial_roi_auto(const vis_calib *c, int width, int height, double l_mm, double dl, int margin_px)
{
    double s = c->px_per_mm;
    double mid_u = 0.5 * (c->clamp_left_px[0] + c->clamp_right_px[0]);
    double mid_v = 0.5 * (c->clamp_left_px[1] + c->clamp_right_px[1]);
    double half_w = 0.5 * l_mm * s;
    double h = fmax(0.5 * l_mm * sqrt(fmax(0.0, 1.0 - (1.0 - dl) * (1.0 - dl))), 0.05 * l_mm) * s;
    trial_roi r;
    r.x = (int)floor(mid_u - half_w) - margin_px;
    r.y = (int)floor(mid_v - h) - margin_px;
    r.w = (int)ceil(2.0 * half_w) + 2 * margin_px;
    r.h = (int)ceil(2.0 * h) + 2 * margin_px;
    return trial_roi_clip(r, width, height);
}

trial_video *trial_video_open(const char *path, trial_roi roi, double fps, char *why, size_t why_len)
{
    trial_video *v = calloc(1, sizeof *v);
    vis_error ve = {0};
    if (!v) {
        snprintf(why, why_len, "video: out of memory");
        return NULL;
    }
    v->roi = roi;
    snprintf(v->path, sizeof v->path, "%s", path);
    snprintf(v->dir, sizeof v->dir, "%s", path);
    char *slash = strrchr(v->dir, '/');
    if (!slash) snprintf(v->dir, sizeof v->dir, ".");
    else if (slash == v->dir) slash[1] = '\0';
    else *slash = '\0';
    v->crop = vis_frame_alloc(roi.w, roi.h, 1, &ve);
    if (v->crop) v->w = vis_video_writer_open(path, roi.w, roi.h, 1, fps, &ve);
    if (!v->crop || !v->w) {
        snprintf(why, why_len, "video %s: %s", path, ve.message);
        vis_frame_free(v->crop);
        free(v);
        return NULL;
    }
    return v;
}

int trial_video_add(trial_video *v, const vis_frame *f, char *why, size_t why_len)
{
    if (vis_frame_channels(f) != 1 || vis_frame_width(f) < v->roi.x + v->roi.w ||
        vis_frame_height(f) < v->roi.y + v->roi.h) {
        snprintf(why, why_len, "video: a %dx%d frame does not hold the region %dx%d+%d+%d", vis_frame_width(f),
                 vis_frame_height(f), v->roi.w, v->roi.h, v->roi.x, v->roi.y);
        return -1;
    }
    /* OpenCV's writer reports no write error: a full disk is seen here, before the frame is lost,
       and fails the trial at once (issue 17, defect 2). */
    struct statvfs fs;
    if (statvfs(v->dir, &fs) == 0) {
        double free_b = (double)fs.f_bavail * (double)fs.f_frsize;
        if (free_b < frame_need_bytes(v) + v->min_free_bytes) {
            snprintf(why, why_len,
                     "video disk full: %.0f bytes free for %s at frame %ld, a frame needs up to %.0f%s; "
                     "the video is incomplete",
                     free_b, v->dir, v->frames, frame_need_bytes(v),
                     v->min_free_bytes > 0 ? " plus the reserve" : "");
            return -1;
        }
    }
    const uint8_t *src = vis_frame_data((vis_frame *)f);
    size_t ss = vis_frame_stride(f), ds = vis_frame_stride(v->crop);
    uint8_t *dst = vis_frame_data(v->crop);
    for (int j = 0; j < v->roi.h; j++)
        memcpy(dst + (size_t)j * ds, src + (size_t)(v->roi.y + j) * ss + (size_t)v->roi.x, (size_t)v->roi.w);
    vis_error ve = {0};
    if (vis_video_writer_write(v->w, v->crop, &ve) != VIS_OK) {
        snprintf(why, why_len, "video: %s", ve.message);
        return -1;
    }
    v->frames++;
    return 0;
}

void trial_video_set_min_free(trial_video *v, double bytes)
{
    if (v) v->min_free_bytes = isfinite(bytes) && bytes > 0 ? bytes : 0.0;
}

long trial_video_close(trial_video *v, char *why, size_t why_len)
{
    if (!v) return 0;
    long n = v->frames;
    vis_video_writer_close(v->w);
    vis_frame_free(v->crop);
    /* Read the container back: a write the encoder lost (a full disk, a file size limit, an I/O
       error) leaves fewer frames in the file than were given, or no count at all. */
    vis_error ve = {0};
    long rc = n;
    if (n > 0) {
        vis_source *src = vis_source_open_video(v->path, &ve);
        int in_file = src ? vis_source_frame_count(src) : -1;
        vis_source_close(src);
        if (in_file != n) {
            if (in_file < 0)
                snprintf(why, why_len, "video incomplete: %s holds no readable frame count (%s) for %ld frames written",
                         v->path, src ? "no index" : ve.message, n);
            else
                snprintf(why, why_len, "video incomplete: %s holds %d of the %ld frames written", v->path, in_file, n);
            rc = -1;
        }
    }
    free(v);
    return rc;
}
