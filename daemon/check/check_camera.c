/* check_camera.c: is the camera a rig file names there, in a format the pipeline reads, at the
 * size its calibration was made for, with an exposure the trial can hold?
 *
 * The probe (check_camera_probe) asks the camera as little as it can: a V4L2 device by ioctls
 * only (its capabilities, VIDIOC_TRY_FMT of the size asked for, the exposure controls), no
 * stream, so a camera in use is not disturbed; a GenICam camera (aravis:) is opened with the rig
 * file's settings as a trial opens it and one frame read. The verdict (check_camera) is kept apart
 * from the probe so that tests can hand it any camera's answer (check_env.camera_probe). The size
 * rule is the trial's (trial_live.c): the calibration's clamp points, and its principal point and
 * optical centre when it has them, must lie inside the camera's frames, and a size the rig file
 * asks for (camera.width_px/height_px) must be the one the camera gives. */
#include <errno.h>
#include <fcntl.h>
#include <linux/videodev2.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "trial.h"
#include "vision.h"

static int xioctl(int fd, unsigned long req, void *arg)
{
    int rc, tries = 0;
    do rc = ioctl(fd, req, arg);
    while (rc < 0 && errno == EINTR && ++tries < 100);
    return rc;
}

static void fourcc_text(unsigned v, char out[8])
{
    for (int i = 0; i < 4; i++) {
        char c = (char)((v >> (8 * i)) & 0xff);
        out[i] = c >= 32 && c < 127 ? c : '?';
    }
    out[4] = 0;
}

static int probe_v4l2(const char *dev, const rig_config *cfg, check_camera_facts *out)
{
    int fd = open(dev, O_RDWR | O_NONBLOCK);
    if (fd < 0) {
        snprintf(out->why, sizeof out->why, "%.200s: %s", dev, strerror(errno));
        return 0;
    }
    struct v4l2_capability cap;
    memset(&cap, 0, sizeof cap);
    if (xioctl(fd, VIDIOC_QUERYCAP, &cap) != 0 || !(cap.device_caps & V4L2_CAP_VIDEO_CAPTURE)) {
        snprintf(out->why, sizeof out->why, "%.200s is not a V4L2 capture device", dev);
        close(fd);
        return 0;
    }
    struct v4l2_format f;
    memset(&f, 0, sizeof f);
    f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd, VIDIOC_G_FMT, &f) != 0) {
        snprintf(out->why, sizeof out->why, "%.200s: VIDIOC_G_FMT: %s", dev, strerror(errno));
        close(fd);
        return 0;
    }
    if (cfg->camera.width_px > 0 && cfg->camera.height_px > 0) { /* what the trial would get */
        f.fmt.pix.width = (unsigned)cfg->camera.width_px;
        f.fmt.pix.height = (unsigned)cfg->camera.height_px;
        xioctl(fd, VIDIOC_TRY_FMT, &f);
    }
    out->found = true;
    fourcc_text(f.fmt.pix.pixelformat, out->fourcc);
    out->width_px = (int)f.fmt.pix.width;
    out->height_px = (int)f.fmt.pix.height;
    /* the trial's own test of the control (vision/source/v4l2_exposure.cpp) */
    int absolute = vis_v4l2_ctrl_settable(NULL, NULL, fd, V4L2_CID_EXPOSURE_ABSOLUTE);
    struct v4l2_control c = {.id = V4L2_CID_EXPOSURE_AUTO, .value = 0};
    int has_auto = xioctl(fd, VIDIOC_G_CTRL, &c) == 0;
    if (absolute && !(cfg->camera.exposure_us > 0)) {
        out->exposure = -1;
        snprintf(out->exposure_text, sizeof out->exposure_text,
                 "exposure_time_absolute settable, but camera.exposure_us is not set: the camera's own exposure%s "
                 "may change between trials", has_auto && c.value != V4L2_EXPOSURE_MANUAL ? " (auto)" : "");
    } else if (absolute) {
        out->exposure = 1;
        snprintf(out->exposure_text, sizeof out->exposure_text, "exposure_time_absolute settable%s",
                 has_auto ? (c.value == V4L2_EXPOSURE_MANUAL ? ", auto exposure off"
                                                             : ", auto exposure on now (a trial switches it off)")
                          : "");
    } else {
        out->exposure = 0;
        snprintf(out->exposure_text, sizeof out->exposure_text, "no settable exposure control%s",
                 has_auto ? " (auto exposure only)" : "");
    }
    close(fd);
    return 0;
}

static int probe_aravis(const rig_config *cfg, check_camera_facts *out)
{
    vis_camera_settings cs = trial_camera_settings(&cfg->camera); /* an aravis source here */
    vis_error ve = {0};
    vis_source *src = vis_source_open_camera(&cs, &ve);
    if (!src) {
        snprintf(out->why, sizeof out->why, "%s", ve.message);
        return 0;
    }
    vis_frame *fr = vis_frame_alloc(16, 16, 1, &ve);
    vis_frame_meta m;
    if (!fr || vis_source_read_meta(src, fr, &m, &ve) != VIS_OK) {
        snprintf(out->why, sizeof out->why, "opened, but no first frame: %s", ve.message);
    } else {
        out->found = true;
        snprintf(out->fourcc, sizeof out->fourcc, "Mono8");
        out->width_px = vis_frame_width(fr);
        out->height_px = vis_frame_height(fr);
        if (cfg->camera.exposure_us > 0) {
            out->exposure = 1;
            snprintf(out->exposure_text, sizeof out->exposure_text, "ExposureTime set to %.0f us (camera.exposure_us)",
                     cfg->camera.exposure_us);
        } else {
            out->exposure = -1;
            snprintf(out->exposure_text, sizeof out->exposure_text,
                     "the camera's own exposure (camera.exposure_us not set): it may change between trials");
        }
    }
    vis_frame_free(fr);
    vis_source_close(src);
    return 0;
}

int check_camera_probe(const rig_config *cfg, check_camera_facts *out)
{
    memset(out, 0, sizeof *out);
    out->exposure = -1;
    char dev[RIG_PATH_MAX + 16];
    switch (cfg->camera.source) {
    case RIG_SOURCE_INDEX:
        snprintf(dev, sizeof dev, "/dev/video%d", cfg->camera.index);
        return probe_v4l2(dev, cfg, out);
    case RIG_SOURCE_DEVICE:
        return probe_v4l2(cfg->camera.device, cfg, out);
    case RIG_SOURCE_ARAVIS:
        return probe_aravis(cfg, out);
    default:
        snprintf(out->why, sizeof out->why, "no live camera source");
        return -1;
    }
}

/* The calibration against frames of w x h: NULL, or the first point outside them. */
static const char *calib_outside(const vis_calib *cal, int w, int h, double *u, double *v)
{
    const double pts[4][2] = {{cal->clamp_left_px[0], cal->clamp_left_px[1]},
                              {cal->clamp_right_px[0], cal->clamp_right_px[1]},
                              {cal->principal_px[0], cal->principal_px[1]},
                              {cal->camera_matrix[2], cal->camera_matrix[5]}};
    static const char *const names[4] = {"left clamp point", "right clamp point", "principal point",
                                         "optical centre"};
    for (int k = 0; k < 4; k++) {
        if (k == 2 && (pts[k][0] < 0 || pts[k][1] < 0)) continue; /* the image centre */
        if (k == 3 && !cal->has_intrinsics) continue;
        if (!(pts[k][0] >= 0 && pts[k][0] < w && pts[k][1] >= 0 && pts[k][1] < h)) {
            *u = pts[k][0];
            *v = pts[k][1];
            return names[k];
        }
    }
    return NULL;
}

void check_camera(const rig_config *cfg, const check_env *env, check_report *r)
{
    const rig_camera *rc = &cfg->camera;
    if (cfg->mode != RIG_MODE_RIG) {
        check_add(r, CHECK_OK, "camera", "source", "%s mode: frames rendered from the simulated ribbon",
                  rig_mode_name(cfg->mode));
        return;
    }
    char what[RIG_PATH_MAX + 32];
    if (rc->source == RIG_SOURCE_INDEX) snprintf(what, sizeof what, "V4L2 /dev/video%d", rc->index);
    else if (rc->source == RIG_SOURCE_DEVICE) snprintf(what, sizeof what, "V4L2 %.900s", rc->device);
    else snprintf(what, sizeof what, "GenICam %.900s", rc->device[0] ? rc->device : "(the first camera)");
    check_camera_facts f;
    memset(&f, 0, sizeof f);
    int (*probe)(const rig_config *, check_camera_facts *) = env->camera_probe ? env->camera_probe : check_camera_probe;
    if (probe(cfg, &f) != 0 || !f.found) {
        check_add(r, CHECK_FAIL, "camera", "found", "%s not found: %s; plug it in and set camera.source "
                  "(ribbonctl cameras lists them)", what, f.why[0] ? f.why : "no answer");
        return;
    }
    check_add(r, CHECK_OK, "camera", "found", "%s", what);
    if (f.fourcc[0])
        check_add(r, CHECK_OK, "camera", "format", "%s", f.fourcc);
    else
        check_add(r, CHECK_WARN, "camera", "format", "the camera did not say its pixel format");
    int size_ok = 1;
    if (rc->width_px > 0 && rc->height_px > 0 && (f.width_px != rc->width_px || f.height_px != rc->height_px)) {
        check_add(r, CHECK_FAIL, "camera", "size", "the camera gives %d x %d, the rig file asks for %d x %d "
                  "(camera.width_px/height_px): set them to a size the camera has", f.width_px, f.height_px,
                  rc->width_px, rc->height_px);
        size_ok = 0;
    }
    vis_calib cal;
    vis_error ve = {0};
    if (!rc->calibration[0]) {
        check_add(r, CHECK_FAIL, "camera", "calib", "no camera.calibration: film the mounted ribbon at zero shear "
                  "and run ribbonctl track FILE --clamp-spacing-mm MM --save-calib rig.calib");
    } else if (vis_calib_load(&cal, rc->calibration, &ve) != VIS_OK) {
        check_add(r, CHECK_FAIL, "camera", "calib", "%.300s: %s", rc->calibration, ve.message);
    } else {
        double u = 0, v = 0;
        const char *bad = calib_outside(&cal, f.width_px, f.height_px, &u, &v);
        if (bad)
            check_add(r, CHECK_FAIL, "camera", "calib", "the calibration does not fit the camera's %d x %d frames: its "
                      "%s (%.1f, %.1f) px is outside them: recalibrate at this size, or set camera.width_px/height_px",
                      f.width_px, f.height_px, bad, u, v);
        else if (size_ok)
            check_add(r, CHECK_OK, "camera", "size", "%d x %d; the calibration's clamp points (%.0f, %.0f) and "
                      "(%.0f, %.0f) px inside", f.width_px, f.height_px, cal.clamp_left_px[0], cal.clamp_left_px[1],
                      cal.clamp_right_px[0], cal.clamp_right_px[1]);
    }
    if (f.exposure == 1)
        check_add(r, CHECK_OK, "camera", "exposure", "%s", f.exposure_text);
    else if (f.exposure == 0)
        check_add(r, CHECK_FAIL, "camera", "exposure", "%s: a trial cannot hold its exposure; use a camera with "
                  "manual exposure", f.exposure_text[0] ? f.exposure_text : "exposure not settable");
    else
        check_add(r, CHECK_WARN, "camera", "exposure", "%s", f.exposure_text[0] ? f.exposure_text : "not known");
}
