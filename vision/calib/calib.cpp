// calib.cpp: the calibration record: defaults, checks, the clamp-points method, and its file.
//
// File format: plain text, one `key = values` per line, `#` comments, numbers separated by commas
// or spaces, written with 17 significant digits so a save/load round-trip is exact. A bad line is
// reported with its number and key. Unknown keys are refused (a typo must not silently fall back
// to a default). Keys: px_per_mm, clamp_left, clamp_right, principal, camera_distance_mm,
// camera_tilt_rad,
// camera_matrix (9 values, row-major), dist (5 values); the last two appear together or not at all.
#include "vis_internal.hpp"
#include "vis_calib.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

extern "C" vis_calib vis_calib_default(void)
{
    vis_calib c;
    std::memset(&c, 0, sizeof c);
    c.px_per_mm = 0.0;  // unset: vis_calib_check refuses it
    c.principal_px[0] = c.principal_px[1] = -1.0;
    return c;
}

extern "C" vis_status vis_calib_check(const vis_calib *c, vis_error *err)
{
    if (!c)
        return vis::fail(err, VIS_ERR_ARG, "calibration: NULL");
    if (!vis::finite(c->px_per_mm) || c->px_per_mm <= 0 || c->px_per_mm > 1e4)
        return vis::fail(err, VIS_ERR_ARG, "calibration: px_per_mm = %g, need 0 < px_per_mm <= 1e4",
                         c->px_per_mm);
    const double v[6] = {c->clamp_left_px[0],  c->clamp_left_px[1], c->clamp_right_px[0],
                         c->clamp_right_px[1], c->principal_px[0],  c->principal_px[1]};
    for (double x : v)
        if (!vis::finite(x) || std::fabs(x) > 1e5)
            return vis::fail(err, VIS_ERR_ARG, "calibration: a clamp or principal point is not finite");
    if (std::hypot(c->clamp_right_px[0] - c->clamp_left_px[0],
                   c->clamp_right_px[1] - c->clamp_left_px[1]) < 4)
        return vis::fail(err, VIS_ERR_ARG, "calibration: clamp points closer than 4 px (unset?)");
    if (!vis::finite(c->camera_distance_mm) || c->camera_distance_mm < 0)
        return vis::fail(err, VIS_ERR_ARG, "calibration: camera_distance_mm must be >= 0");
    if (!vis::finite(c->camera_tilt_rad) || std::fabs(c->camera_tilt_rad) > 1.2)
        return vis::fail(err, VIS_ERR_ARG, "calibration: camera_tilt_rad must be within +-1.2");
    if (c->has_intrinsics) {
        for (int i = 0; i < 9; i++)
            if (!vis::finite(c->camera_matrix[i]))
                return vis::fail(err, VIS_ERR_ARG, "calibration: camera_matrix not finite");
        for (int i = 0; i < 5; i++)
            if (!vis::finite(c->dist[i]))
                return vis::fail(err, VIS_ERR_ARG, "calibration: dist not finite");
        if (!(c->camera_matrix[0] > 0 && c->camera_matrix[4] > 0))
            return vis::fail(err, VIS_ERR_ARG, "calibration: camera_matrix focal lengths must be > 0");
    }
    vis::ok(err);
    return VIS_OK;
}

extern "C" vis_status vis_calib_from_clamps(vis_calib *c, const double left_px[2],
                                            const double right_px[2], double spacing_mm,
                                            vis_error *err)
{
    if (!c || !left_px || !right_px)
        return vis::fail(err, VIS_ERR_ARG, "vis_calib_from_clamps: NULL argument");
    if (!vis::finite(spacing_mm) || spacing_mm <= 0)
        return vis::fail(err, VIS_ERR_ARG, "clamp spacing %g mm must be > 0", spacing_mm);
    const double d = std::hypot(right_px[0] - left_px[0], right_px[1] - left_px[1]);
    if (!vis::finite(d) || d < 4)
        return vis::fail(err, VIS_ERR_ARG, "clamp points %.1f px apart: need at least 4 px", d);
    c->clamp_left_px[0] = left_px[0];
    c->clamp_left_px[1] = left_px[1];
    c->clamp_right_px[0] = right_px[0];
    c->clamp_right_px[1] = right_px[1];
    c->px_per_mm = d / spacing_mm;
    return vis_calib_check(c, err);
}

extern "C" vis_status vis_calib_from_camera(vis_calib *c, const vis_camera *cam, const double left_m[3],
                                            const double right_m[3], vis_error *err)
{
    if (!c || !cam || !left_m || !right_m)
        return vis::fail(err, VIS_ERR_ARG, "vis_calib_from_camera: NULL argument");
    const double l[3] = {left_m[0], 0.0, left_m[2]}, r[3] = {right_m[0], 0.0, right_m[2]};
    vis_calib out = vis_calib_default();
    vis_status st = vis_camera_project(cam, l, out.clamp_left_px, err);
    if (st == VIS_OK)
        st = vis_camera_project(cam, r, out.clamp_right_px, err);
    if (st != VIS_OK)
        return st;
    out.px_per_mm = cam->focal_px / cam->distance_m / 1000.0;
    out.camera_distance_mm = cam->distance_m * 1000.0;
    out.camera_tilt_rad = cam->tilt_rad;
    out.principal_px[0] = 0.5 * (cam->width_px - 1);
    out.principal_px[1] = 0.5 * (cam->height_px - 1);
    st = vis_calib_check(&out, err);
    if (st == VIS_OK)
        *c = out;
    return st;
}

extern "C" vis_status vis_calib_save(const vis_calib *c, const char *path, vis_error *err)
{
    if (!path)
        return vis::fail(err, VIS_ERR_ARG, "vis_calib_save: NULL path");
    vis_status s = vis_calib_check(c, err);
    if (s != VIS_OK)
        return s;
    FILE *f = std::fopen(path, "w");
    if (!f)
        return vis::fail(err, VIS_ERR_IO, "cannot write calibration %s: %s", path, std::strerror(errno));
    std::fprintf(f, "# ribbon rig camera calibration (vision/calib.cpp)\n");
    std::fprintf(f, "px_per_mm = %.17g\n", c->px_per_mm);
    std::fprintf(f, "clamp_left = %.17g, %.17g\n", c->clamp_left_px[0], c->clamp_left_px[1]);
    std::fprintf(f, "clamp_right = %.17g, %.17g\n", c->clamp_right_px[0], c->clamp_right_px[1]);
    std::fprintf(f, "principal = %.17g, %.17g\n", c->principal_px[0], c->principal_px[1]);
    std::fprintf(f, "camera_distance_mm = %.17g\n", c->camera_distance_mm);
    std::fprintf(f, "camera_tilt_rad = %.17g\n", c->camera_tilt_rad);
    if (c->has_intrinsics) {
        std::fprintf(f, "camera_matrix =");
        for (int i = 0; i < 9; i++)
            std::fprintf(f, "%s %.17g", i ? "," : "", c->camera_matrix[i]);
        std::fprintf(f, "\ndist =");
        for (int i = 0; i < 5; i++)
            std::fprintf(f, "%s %.17g", i ? "," : "", c->dist[i]);
        std::fprintf(f, "\n");
    }
    if (std::fclose(f) != 0)
        return vis::fail(err, VIS_ERR_IO, "cannot write calibration %s", path);
    vis::ok(err);
    return VIS_OK;
}

// Parse exactly `n` numbers from `s`; false on any other content.
static bool parse_numbers(const char *s, double *out, int n)
{
    for (int i = 0; i < n; i++) {
        while (*s == ' ' || *s == '\t' || (i > 0 && *s == ','))
            s++;
        // Plain decimal only, as every number from outside (docs/hostile-input.md): strtod is
        // given only the characters of a decimal number, so hex floats, inf and nan never reach
        // it (vision/ is a floor below config/, whose cfg_number holds the grammar for the rest).
        size_t span = std::strspn(s, "0123456789+-.eE");
        if (span == 0 || span >= 64)
            return false;
        char num[64];
        std::memcpy(num, s, span);
        num[span] = '\0';
        char *end;
        errno = 0;
        out[i] = std::strtod(num, &end);
        if (end != num + span || !std::isfinite(out[i]) || (out[i] != 0 && std::fabs(out[i]) < 2.2250738585072014e-308))
            return false;
        s += span;
    }
    while (*s == ' ' || *s == '\t' || *s == '\r' || *s == '\n')
        s++;
    return *s == '\0';
}

extern "C" vis_status vis_calib_load(vis_calib *c, const char *path, vis_error *err)
{
    if (!c || !path)
        return vis::fail(err, VIS_ERR_ARG, "vis_calib_load: NULL argument");
    // Only a regular file: opened without blocking (a FIFO would wait for a writer for ever).
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0)
        return vis::fail(err, VIS_ERR_IO, "cannot read calibration %s: %s", path, std::strerror(errno));
    struct stat fst;
    if (fstat(fd, &fst) != 0 || !S_ISREG(fst.st_mode)) {
        close(fd);
        return vis::fail(err, VIS_ERR_IO, "cannot read calibration %s: not a regular file", path);
    }
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    FILE *f = fdopen(fd, "r");
    if (!f) {
        close(fd);
        return vis::fail(err, VIS_ERR_IO, "cannot read calibration %s: %s", path, std::strerror(errno));
    }
    vis_calib r = vis_calib_default();
    char line[1024];
    int lineno = 0, have_k = 0, have_d = 0;
    vis_status st = VIS_OK;
    while (st == VIS_OK && lineno < 10000 && std::fgets(line, sizeof line, f)) {
        lineno++;
        if (!std::strchr(line, '\n') && !std::feof(f)) {
            st = vis::fail(err, VIS_ERR_FORMAT, "%s:%d: line too long", path, lineno);
            break;
        }
        char *p = line;
        while (*p == ' ' || *p == '\t')
            p++;
        if (*p == '#' || *p == '\n' || *p == '\r' || *p == '\0')
            continue;
        char *eq = std::strchr(p, '=');
        if (!eq) {
            st = vis::fail(err, VIS_ERR_FORMAT, "%s:%d: expected key = value", path, lineno);
            break;
        }
        char *ke = eq;
        while (ke > p && (ke[-1] == ' ' || ke[-1] == '\t'))
            ke--;
        *ke = '\0';
        const char *val = eq + 1;
        struct Key {
            const char *name;
            double *dst;
            int n;
            int *flag;
        } keys[] = {{"px_per_mm", &r.px_per_mm, 1, nullptr},
                    {"clamp_left", r.clamp_left_px, 2, nullptr},
                    {"clamp_right", r.clamp_right_px, 2, nullptr},
                    {"principal", r.principal_px, 2, nullptr},
                    {"camera_distance_mm", &r.camera_distance_mm, 1, nullptr},
                    {"camera_tilt_rad", &r.camera_tilt_rad, 1, nullptr},
                    {"camera_matrix", r.camera_matrix, 9, &have_k},
                    {"dist", r.dist, 5, &have_d}};
        bool known = false;
        for (const Key &k : keys) {
            if (std::strcmp(p, k.name) != 0)
                continue;
            known = true;
            if (!parse_numbers(val, k.dst, k.n))
                st = vis::fail(err, VIS_ERR_FORMAT, "%s:%d: %s needs %d finite number%s", path, lineno,
                               k.name, k.n, k.n > 1 ? "s" : "");
            else if (k.flag)
                *k.flag = 1;
        }
        if (!known)
            st = vis::fail(err, VIS_ERR_FORMAT, "%s:%d: unknown key \"%s\"", path, lineno, p);
    }
    std::fclose(f);
    if (st != VIS_OK)
        return st;
    if (have_k != have_d)
        return vis::fail(err, VIS_ERR_FORMAT, "%s: camera_matrix and dist must appear together", path);
    r.has_intrinsics = have_k;
    vis_error e2;
    if (vis_calib_check(&r, &e2) != VIS_OK)
        return vis::fail(err, VIS_ERR_FORMAT, "%s: %s", path, e2.message);
    *c = r;
    vis::ok(err);
    return VIS_OK;
}
