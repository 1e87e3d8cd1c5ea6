/* test_vision_v4l2_exposure.c: a V4L2 camera's exposure and gain held for a trial
 * (vis_v4l2_hold_exposure), against a fake control set handed in as the ioctl: a camera that holds
 * what it is told (auto exposure switched off, exposure in 100 us units, auto gain off, gain set and
 * read back), and one per way a camera cannot hold them, each refused with the control named: no
 * exposure control, auto exposure that cannot be switched off, a value out of range or off its step,
 * a driver that clamps (read back differs), no gain control. No device is opened. */
#include <errno.h>
#include <linux/videodev2.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "vision.h"

/* One fake control: its description, its value, and how the "driver" treats writes. */
typedef struct fake_ctrl {
    unsigned id;
    int present, min, max, step, flags, value;
    int refuse_write; /* S_CTRL fails with EINVAL */
    int clamp_to;     /* > 0: a write stores this instead (a driver that clamps silently) */
    int writes;
} fake_ctrl;

typedef struct fake_cam {
    fake_ctrl c[5]; /* auto exposure, exposure absolute, auto gain, gain, analogue gain */
} fake_cam;

static fake_ctrl *find(fake_cam *cam, unsigned id)
{
    for (int i = 0; i < 5; i++)
        if (cam->c[i].id == id && cam->c[i].present) return &cam->c[i];
    return NULL;
}

static int fake_ioctl(void *user, int fd, unsigned long req, void *arg)
{
    (void)fd;
    fake_cam *cam = user;
    if (req == VIDIOC_QUERYCTRL) {
        struct v4l2_queryctrl *q = arg;
        fake_ctrl *c = find(cam, q->id);
        if (!c) { errno = EINVAL; return -1; }
        q->minimum = c->min;
        q->maximum = c->max;
        q->step = c->step;
        q->flags = (unsigned)c->flags;
        return 0;
    }
    if (req == VIDIOC_G_CTRL || req == VIDIOC_S_CTRL) {
        struct v4l2_control *v = arg;
        fake_ctrl *c = find(cam, v->id);
        if (!c) { errno = EINVAL; return -1; }
        if (req == VIDIOC_G_CTRL) { v->value = c->value; return 0; }
        if (c->refuse_write) { errno = EINVAL; return -1; }
        c->value = c->clamp_to > 0 ? c->clamp_to : v->value;
        c->writes++;
        return 0;
    }
    errno = ENOTTY;
    return -1;
}

/* A UVC-like camera: auto exposure on (aperture priority), exposure 1..5000 (100 us .. 0.5 s),
 * auto gain on, gain 0..255. */
static fake_cam uvc(void)
{
    fake_cam cam = {{
        {V4L2_CID_EXPOSURE_AUTO, 1, 0, 3, 1, 0, V4L2_EXPOSURE_APERTURE_PRIORITY, 0, 0, 0},
        {V4L2_CID_EXPOSURE_ABSOLUTE, 1, 1, 5000, 1, V4L2_CTRL_FLAG_INACTIVE, 156, 0, 0, 0},
        {V4L2_CID_AUTOGAIN, 1, 0, 1, 1, 0, 1, 0, 0, 0},
        {V4L2_CID_GAIN, 1, 0, 255, 1, 0, 32, 0, 0, 0},
        {V4L2_CID_ANALOGUE_GAIN, 0, 0, 0, 0, 0, 0, 0, 0, 0},
    }};
    return cam;
}

static vis_status hold(fake_cam *cam, double exposure_us, double gain, vis_error *err)
{
    memset(err, 0, sizeof *err);
    return vis_v4l2_hold_exposure(fake_ioctl, cam, 3, "/dev/video9", exposure_us, gain, err);
}

static void assert_refused(vis_status st, const vis_error *err, const char *needle)
{
    assert_int_equal(st, VIS_ERR_ARG);
    if (!strstr(err->message, needle)) fail_msg("message \"%s\" does not name \"%s\"", err->message, needle);
    assert_non_null(strstr(err->message, "/dev/video9"));
}

static void test_held(void **state)
{
    (void)state;
    fake_cam cam = uvc();
    vis_error err;
    assert_int_equal(hold(&cam, 2000, 40, &err), VIS_OK);
    assert_int_equal(cam.c[0].value, V4L2_EXPOSURE_MANUAL); /* auto exposure off */
    assert_int_equal(cam.c[1].value, 20);                   /* 2000 us in 100 us units */
    assert_int_equal(cam.c[2].value, 0);                    /* auto gain off */
    assert_int_equal(cam.c[3].value, 40);
}

static void test_nothing_asked_nothing_touched(void **state)
{
    (void)state;
    fake_cam cam = uvc();
    vis_error err;
    assert_int_equal(hold(&cam, 0, -1, &err), VIS_OK);
    for (int i = 0; i < 5; i++) assert_int_equal(cam.c[i].writes, 0);
    /* exposure alone leaves auto gain and gain as they are */
    assert_int_equal(hold(&cam, 100, -1, &err), VIS_OK);
    assert_int_equal(cam.c[1].value, 1);
    assert_int_equal(cam.c[2].writes + cam.c[3].writes, 0);
}

static void test_analogue_gain_when_no_gain(void **state)
{
    (void)state;
    fake_cam cam = uvc();
    cam.c[3].present = 0;
    cam.c[4] = (fake_ctrl){V4L2_CID_ANALOGUE_GAIN, 1, 16, 1023, 1, 0, 16, 0, 0, 0};
    vis_error err;
    assert_int_equal(hold(&cam, 0, 100, &err), VIS_OK);
    assert_int_equal(cam.c[4].value, 100);
}

static void test_no_exposure_control(void **state)
{
    (void)state;
    fake_cam cam = uvc();
    cam.c[1].present = 0;
    vis_error err;
    assert_refused(hold(&cam, 2000, -1, &err), &err, "no exposure_time_absolute control");
    cam = uvc();
    cam.c[1].flags = V4L2_CTRL_FLAG_DISABLED;
    assert_refused(hold(&cam, 2000, -1, &err), &err, "no exposure_time_absolute control");
    cam = uvc();
    cam.c[1].flags = V4L2_CTRL_FLAG_READ_ONLY;
    assert_refused(hold(&cam, 2000, -1, &err), &err, "exposure_time_absolute cannot be set");
}

static void test_auto_exposure_stays_on(void **state)
{
    (void)state;
    fake_cam cam = uvc();
    cam.c[0].refuse_write = 1; /* a camera whose menu lacks manual */
    vis_error err;
    assert_refused(hold(&cam, 2000, -1, &err), &err, "auto exposure cannot be switched off");
    assert_int_equal(cam.c[1].writes, 0);
    cam = uvc();
    cam.c[0].clamp_to = V4L2_EXPOSURE_APERTURE_PRIORITY; /* accepts the write, stays automatic */
    assert_refused(hold(&cam, 2000, -1, &err), &err, "auto exposure cannot be switched off");
    cam = uvc();
    cam.c[2].refuse_write = 1;
    assert_refused(hold(&cam, 0, 40, &err), &err, "auto gain cannot be switched off");
}

static void test_out_of_range_and_step(void **state)
{
    (void)state;
    fake_cam cam = uvc();
    vis_error err;
    assert_refused(hold(&cam, 600000, -1, &err), &err, "exposure_time_absolute 600000 us refused: the camera allows 100..500000 us");
    assert_int_equal(cam.c[1].writes, 0);
    assert_refused(hold(&cam, 150, -1, &err), &err, "whole 100 us units");
    assert_refused(hold(&cam, 40, -1, &err), &err, "whole 100 us units");
    cam.c[1].step = 10;
    assert_refused(hold(&cam, 2500, -1, &err), &err, "in steps of 1000 us");
    assert_refused(hold(&cam, 0, 300, &err), &err, "gain 300 refused: the camera allows 0..255");
    assert_refused(hold(&cam, 0, 2.5, &err), &err, "whole number");
}

static void test_read_back_differs(void **state)
{
    (void)state;
    fake_cam cam = uvc();
    cam.c[1].clamp_to = 19;
    vis_error err;
    assert_refused(hold(&cam, 2000, -1, &err), &err, "exposure_time_absolute 2000 us refused (it is 1900 us)");
    cam = uvc();
    cam.c[3].clamp_to = 39;
    assert_refused(hold(&cam, 0, 40, &err), &err, "gain 40 refused (it is 39)");
    cam = uvc();
    cam.c[3].refuse_write = 1;
    assert_refused(hold(&cam, 0, 40, &err), &err, "gain 40 refused: Invalid argument");
}

static void test_no_gain_control(void **state)
{
    (void)state;
    fake_cam cam = uvc();
    cam.c[3].present = 0;
    vis_error err;
    assert_refused(hold(&cam, 0, 40, &err), &err, "no gain or analogue_gain control");
}

static void test_settable_probe(void **state)
{
    (void)state;
    fake_cam cam = uvc();
    assert_int_equal(vis_v4l2_ctrl_settable(fake_ioctl, &cam, 3, V4L2_CID_EXPOSURE_ABSOLUTE), 1);
    cam.c[1].flags = V4L2_CTRL_FLAG_READ_ONLY;
    assert_int_equal(vis_v4l2_ctrl_settable(fake_ioctl, &cam, 3, V4L2_CID_EXPOSURE_ABSOLUTE), 0);
    cam.c[1].present = 0;
    assert_int_equal(vis_v4l2_ctrl_settable(fake_ioctl, &cam, 3, V4L2_CID_EXPOSURE_ABSOLUTE), 0);
}

/* gain_db on a V4L2 camera is refused by the opener itself, before the device is touched (there is
 * no device here: without the refusal the error would be the device's). */
static void test_open_refuses_gain_db(void **state)
{
    (void)state;
    vis_camera_settings cs = vis_camera_settings_default();
    cs.path = "/nonexistent/video-v4l2-test";
    cs.gain_db = 6;
    vis_error err = {0};
    assert_null(vis_source_open_camera(&cs, &err));
    assert_int_equal(err.code, VIS_ERR_ARG);
    assert_non_null(strstr(err.message, "gain 6 dB refused: a V4L2 camera's gain has no dB scale"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_held),
        cmocka_unit_test(test_nothing_asked_nothing_touched),
        cmocka_unit_test(test_analogue_gain_when_no_gain),
        cmocka_unit_test(test_no_exposure_control),
        cmocka_unit_test(test_auto_exposure_stays_on),
        cmocka_unit_test(test_out_of_range_and_step),
        cmocka_unit_test(test_read_back_differs),
        cmocka_unit_test(test_no_gain_control),
        cmocka_unit_test(test_settable_probe),
        cmocka_unit_test(test_open_refuses_gain_db),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
