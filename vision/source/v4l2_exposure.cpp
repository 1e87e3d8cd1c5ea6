// v4l2_exposure.cpp: a V4L2 camera's exposure and gain, held for a trial or the camera refused.
//
// A trial compares brightness-dependent edges frame to frame, so a camera that changes its own
// exposure or gain during a trial is refused rather than used. Order: auto exposure
// (V4L2_CID_EXPOSURE_AUTO) switched to V4L2_EXPOSURE_MANUAL first, since UVC drivers mark the
// absolute exposure inactive while auto is on; then V4L2_CID_EXPOSURE_ABSOLUTE, in its 100 us
// units; then auto gain (V4L2_CID_AUTOGAIN) off and the gain (V4L2_CID_GAIN, else
// V4L2_CID_ANALOGUE_GAIN; V4L2 gives gain no unit, so it is written in the control's own units).
// Each value is checked against the control's range and step before it is written (a driver may
// clamp silently), and read back after (VIDIOC_G_CTRL): any difference refuses the camera, with the
// control, the value asked and what the camera allows or holds. The ioctl is a parameter, so the
// whole logic runs in tests against a fake control set, with no device (tests/vision/
// test_vision_v4l2_exposure.c); `ribbonctl check` shares vis_v4l2_ctrl_settable.
#include "source.hpp"

#include <linux/videodev2.h>
#include <sys/ioctl.h>

#include <cerrno>
#include <cmath>
#include <cstring>

namespace vis {
namespace {

int real_ioctl(void *, int fd, unsigned long req, void *arg)
{
    return ::ioctl(fd, req, arg);
}

struct Dev {
    vis_ioctl_fn io;
    void *user;
    int fd;
    const char *name;

    int call(unsigned long req, void *arg) const
    {
        int rc, tries = 0;
        do {
            errno = 0;
            rc = io(user, fd, req, arg);
        } while (rc < 0 && errno == EINTR && ++tries < 100);
        return rc;
    }
    // The control's description, or false when the camera has no such control.
    bool query(unsigned id, v4l2_queryctrl &q) const
    {
        std::memset(&q, 0, sizeof q);
        q.id = id;
        return call(VIDIOC_QUERYCTRL, &q) == 0 && !(q.flags & V4L2_CTRL_FLAG_DISABLED);
    }
    bool get(unsigned id, int &v) const
    {
        v4l2_control c;
        c.id = id;
        c.value = 0;
        if (call(VIDIOC_G_CTRL, &c) != 0)
            return false;
        v = c.value;
        return true;
    }
};

// Writes `v` to control `id` (described by q, called `what`) and reads it back; `scale` and
// `unit` say the value in the user's units in messages (exposure: 100 us units shown in us).
vis_status write_held(const Dev &d, const v4l2_queryctrl &q, const char *what, int v, double scale,
                      const char *unit, vis_error *err)
{
    if (q.flags & V4L2_CTRL_FLAG_READ_ONLY)
        return fail(err, VIS_ERR_ARG, "camera %s: %s cannot be set (read-only control)", d.name, what);
    if (v < q.minimum || v > q.maximum)
        return fail(err, VIS_ERR_ARG, "camera %s: %s %g%s refused: the camera allows %g..%g%s", d.name, what,
                    v * scale, unit, q.minimum * scale, q.maximum * scale, unit);
    if (q.step > 1 && (v - q.minimum) % q.step != 0)
        return fail(err, VIS_ERR_ARG, "camera %s: %s %g%s refused: the camera allows %g..%g%s in steps of %g%s",
                    d.name, what, v * scale, unit, q.minimum * scale, q.maximum * scale, unit, q.step * scale, unit);
    v4l2_control c;
    c.id = q.id;
    c.value = v;
    if (d.call(VIDIOC_S_CTRL, &c) != 0)
        return fail(err, VIS_ERR_ARG, "camera %s: %s %g%s refused: %s", d.name, what, v * scale, unit,
                    std::strerror(errno ? errno : EIO));
    int got = 0;
    if (!d.get(q.id, got))
        return fail(err, VIS_ERR_ARG, "camera %s: %s cannot be read back: %s", d.name, what,
                    std::strerror(errno ? errno : EIO));
    if (got != v)
        return fail(err, VIS_ERR_ARG, "camera %s: %s %g%s refused (it is %g%s)", d.name, what, v * scale, unit,
                    got * scale, unit);
    return VIS_OK;
}

// An automatic control (auto exposure or auto gain) switched to `manual` and read back; a camera
// without it has nothing to switch off.
vis_status auto_off(const Dev &d, unsigned id, int manual, const char *what, vis_error *err)
{
    v4l2_queryctrl q;
    if (!d.query(id, q))
        return VIS_OK;
    int now = 0;
    if (d.get(id, now) && now == manual)
        return VIS_OK;
    v4l2_control c;
    c.id = id;
    c.value = manual;
    if ((q.flags & V4L2_CTRL_FLAG_READ_ONLY) || d.call(VIDIOC_S_CTRL, &c) != 0)
        return fail(err, VIS_ERR_ARG, "camera %s: %s cannot be switched off (%s): a trial cannot hold its %s",
                    d.name, what, (q.flags & V4L2_CTRL_FLAG_READ_ONLY) ? "read-only control"
                                                                        : std::strerror(errno ? errno : EIO),
                    id == V4L2_CID_EXPOSURE_AUTO ? "exposure" : "gain");
    if (!d.get(id, now) || now != manual)
        return fail(err, VIS_ERR_ARG, "camera %s: %s cannot be switched off (it reads back %d): a trial cannot "
                    "hold its %s", d.name, what, now, id == V4L2_CID_EXPOSURE_AUTO ? "exposure" : "gain");
    return VIS_OK;
}

vis_status hold_exposure(const Dev &d, double exposure_us, vis_error *err)
{
    const double units = std::round(exposure_us / 100.0);  // V4L2_CID_EXPOSURE_ABSOLUTE: 100 us
    if (!(units >= 1 && units <= 2147483647.0) || !(std::fabs(units * 100.0 - exposure_us) <= 1e-3 * exposure_us + 1.0))
        return fail(err, VIS_ERR_ARG, "camera %s: exposure %g us refused: a V4L2 camera's exposure_time_absolute "
                    "counts whole 100 us units", d.name, exposure_us);
    vis_status st = auto_off(d, V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL, "auto exposure", err);
    if (st != VIS_OK)
        return st;
    v4l2_queryctrl q;
    if (!d.query(V4L2_CID_EXPOSURE_ABSOLUTE, q))
        return fail(err, VIS_ERR_ARG, "camera %s: no exposure_time_absolute control: a trial cannot hold its "
                    "exposure (exposure %g us asked)", d.name, exposure_us);
    return write_held(d, q, "exposure_time_absolute", (int)units, 100.0, " us", err);
}

vis_status hold_gain(const Dev &d, double gain, vis_error *err)
{
    if (!(gain >= 0 && gain <= 2147483647.0) || gain != std::floor(gain))
        return fail(err, VIS_ERR_ARG, "camera %s: gain %g refused: a V4L2 gain is a whole number in the control's "
                    "own units", d.name, gain);
    v4l2_queryctrl q;
    const char *what = "gain";
    if (!d.query(V4L2_CID_GAIN, q)) {
        what = "analogue_gain";
        if (!d.query(V4L2_CID_ANALOGUE_GAIN, q))
            return fail(err, VIS_ERR_ARG, "camera %s: no gain or analogue_gain control: gain %g cannot be set",
                        d.name, gain);
    }
    vis_status st = auto_off(d, V4L2_CID_AUTOGAIN, 0, "auto gain", err);
    if (st != VIS_OK)
        return st;
    return write_held(d, q, what, (int)gain, 1.0, "", err);
}

}  // namespace
}  // namespace vis

extern "C" int vis_v4l2_ctrl_settable(vis_ioctl_fn io, void *user, int fd, unsigned id)
{
    const vis::Dev d = {io ? io : vis::real_ioctl, user, fd, ""};
    v4l2_queryctrl q;
    return d.query(id, q) && !(q.flags & V4L2_CTRL_FLAG_READ_ONLY);
}

extern "C" vis_status vis_v4l2_hold_exposure(vis_ioctl_fn io, void *user, int fd, const char *name,
                                             double exposure_us, double gain, vis_error *err)
{
    const vis::Dev d = {io ? io : vis::real_ioctl, user, fd, name ? name : "?"};
    if (exposure_us > 0) {
        vis_status st = vis::hold_exposure(d, exposure_us, err);
        if (st != VIS_OK)
            return st;
    }
    if (gain >= 0)
        return vis::hold_gain(d, gain, err);
    return VIS_OK;
}
