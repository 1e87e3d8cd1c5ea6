/* ctl_track.c: `ribbonctl track`: measure Delta Z and A in every frame of a recorded video.
 *
 *   ribbonctl track VIDEO|PATTERN [--calib FILE | SCALE [--clamp-left X,Y --clamp-right X,Y]]
 *                   [--camera-distance-mm D] [--camera-tilt-rad T] [--shear-csv FILE] [--length-mm L]
 *                   [--polarity auto|dark|light] [--csv OUT] [--overlay OUT.mkv]
 *                   [--save-calib FILE] [--depth-scene SCENE [--depth-set section.key=value ...]]
 *                   [--threads N] [--refresh-frames K] [--json] [--quiet]
 *   SCALE: --px-per-mm S | --clamp-spacing-mm MM | --length-mm L alone
 *
 * PATTERN: an image sequence such as dir/frame_%04d.png (numbered from 0).
 * Without --calib the calibration is put together from two independent parts. Clamp points: given,
 * or found (vis_find_clamps) in the first frame where a clamp pair shows, at zero shear; frames before
 * it are reported as clamp_not_found. Scale: --px-per-mm, the clamp spacing, or, with --length-mm
 * alone, the ribbon's measured length in the first tracked frame (tracked in pixels first; Delta Z is
 * a ratio of lengths, so pixels suffice, and the frame is then measured again in the calibration so
 * found). --save-calib writes the calibration once it is complete.
 * Reads the video through vision's frame source, tracks every frame, writes one CSV row per frame
 * (frame, t, dz, a, quality, reason: dz and a empty when the frame has no measurement, never NaN),
 * optionally an FFV1 overlay video, and prints a summary (--json: frames, tracked, mean_quality,
 * snap_frame, damaged, error, tracking_threads (the cores that tracked; 1 for the serial loop),
 * and the calibration used: px_per_mm, clamp_left, clamp_right,
 * clamps_frame where the clamps were found, null when given or never found; depth_shapes, the
 * predicted shapes taken for the depth, null without --depth-scene). A progress bar goes to stderr. A video that stops before its
 * announced length is read up to the damage; the outputs keep every frame read, the damage is
 * reported and the exit status is 1. Exit status: 0 done, 1 input or output failed, 2 usage.
 * --shear-csv gives the shear rail position per frame (lines "frame,shear_mm", header allowed) for
 * the depth correction; frames not listed take the last value given (0 before the first).
 * --depth-scene predicts the scene (rod_predict, adaptive steps, 2 s after the snap) before the
 * frames are read and gives the tracker the prediction's shapes as its depth (twin_depth.h,
 * docs/vision.md "Depth"): each frame is measured at the depth of the predicted shape nearest to
 * what it shows, instead of the default profile. Only worth it with the camera close (about 1 m
 * for a 200 mm strip) and only as good as the prediction of the snap; the default is off.
 * Once the calibration is complete the frames go through vis_track_pipe: the stretches between
 * the tracker's refresh points (--refresh-frames, 100 by default) are tracked on --threads cores
 * (0, the default: all; 1: the plain serial loop), every result bit for bit the serial loop's. */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctl.h"
#include "cfg_number.h"
#include "rod_protocol.h"
#include "scene_file.h"
#include "twin.h"
#include "vision.h"

#define TRACK_MAX_FRAMES 50000000 /* loop cap: about 19 days at 30 fps */
#define TRACK_MAX_DEPTH_SETS 64
#define TRACK_UV_MAX 65536 /* centreline points kept for the overlay */

typedef struct track_cli {
    const char *video, *calib_file, *csv, *overlay, *save_calib, *shear_csv;
    const char *depth_scene;                       /* --depth-scene (NULL: the default profile) */
    const char *depth_sets[TRACK_MAX_DEPTH_SETS];  /* --depth-set overrides */
    int n_depth_sets;
    vis_depth_library depth;                       /* the prediction's shapes (n_shapes 0: none) */
    double px_per_mm, spacing_mm, distance_mm, tilt_rad;
    int have_tilt;
    double left[2], right[2];
    int have_left, have_right, json, quiet;
    int threads;                                   /* --threads: 0 all cores, 1 serial */
    vis_track_params tp;
} track_cli;

/* Where the calibration stands while frames are read (without --calib it completes on the way). */
typedef struct track_cal {
    vis_calib cal;       /* complete once have_clamps && !scale_pending */
    int have_clamps;     /* clamp points known (given or found) */
    int scale_pending;   /* scale to come from --length-mm and the first tracked frame */
    char why[300];       /* last reason the clamps were not found */
} track_cal;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ribbonctl track VIDEO|IMAGE_PATTERN [calibration] [options]\n"
            "  IMAGE_PATTERN: an image sequence such as dir/frame_%%04d.png, numbered from 0\n"
            "calibration: --calib FILE (saved calibration), or a scale and, optionally, clamp points\n"
            "  scale (one of):\n"
            "    --px-per-mm S             pixels per mm in the ribbon's plane\n"
            "    --clamp-spacing-mm MM     from the clamp points and their known spacing\n"
            "    --length-mm L             with neither of the above: from the ribbon's length in\n"
            "                              the first tracked frame (take it at zero shear)\n"
            "  clamp points: --clamp-left X,Y --clamp-right X,Y, pixel coordinates of the ribbon's\n"
            "    centre where it leaves each clamp, at zero shear; when not given they are found in\n"
            "    the first frame that shows both clamp jaws (at zero shear), and earlier frames are\n"
            "    reported as clamp_not_found\n"
            "options:\n"
            "  --camera-distance-mm D   camera to ribbon plane, enables the depth correction\n"
            "  --camera-tilt-rad T      camera pitch, positive looking down (with a distance)\n"
            "  --shear-csv FILE         shear rail position per frame: lines frame,shear_mm\n"
            "  --length-mm L            free length l for Delta Z = dz / l (default: measured)\n"
            "  --polarity auto|dark|light\n"
            "  --csv OUT                per-frame CSV: frame,t,dz,a,quality,reason\n"
            "  --overlay OUT.mkv        overlay video (FFV1)\n"
            "  --save-calib FILE        write the calibration used (given or found)\n"
            "  --depth-scene SCENE      predict this scene first and take each frame's depth from\n"
            "                           the predicted shape nearest to it (docs/vision.md, Depth):\n"
            "                           for a camera close to the ribbon; default: the clamped\n"
            "                           shear profile. --length-mm defaults to the scene's length\n"
            "  --depth-set K=V          override in that scene, section.key=value (repeatable)\n"
            "  --threads N              cores that track (0, the default: all; 1: the serial loop);\n"
            "                           the results are the same whatever N\n"
            "  --refresh-frames K       acquire from scratch every K frames (100; 0: never): the\n"
            "                           stretches between are what the cores share\n"
            "  --json                   summary as JSON on stdout\n"
            "  --quiet                  no progress bar\n");
}

static int parse_num(const char *opt, const char *v, double *out)
{
    char *end = NULL;
    const double x = v ? cfg_number_strtod(v, &end) : NAN;
    if (!v || end == v || *end || !isfinite(x)) {
        fprintf(stderr, "ribbonctl track: %s needs a number, got '%s'\n", opt, v ? v : "");
        return -1;
    }
    *out = x;
    return 0;
}

static int parse_point(const char *opt, const char *v, double out[2])
{
    char *end = NULL;
    if (!v) {
        fprintf(stderr, "ribbonctl track: %s needs X,Y\n", opt);
        return -1;
    }
    out[0] = cfg_number_strtod(v, &end);
    if (end == v || *end != ',') {
        fprintf(stderr, "ribbonctl track: %s needs X,Y (pixels), got '%s'\n", opt, v);
        return -1;
    }
    const char *w = end + 1;
    out[1] = cfg_number_strtod(w, &end);
    if (end == w || *end || !isfinite(out[0]) || !isfinite(out[1])) {
        fprintf(stderr, "ribbonctl track: %s needs X,Y (pixels), got '%s'\n", opt, v);
        return -1;
    }
    return 0;
}

static int parse_args(int argc, char **argv, track_cli *c)
{
    memset(c, 0, sizeof *c);
    c->tp = vis_track_params_default();
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        int used = 1; /* this option takes a value */
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 1;
        } else if (!strcmp(a, "--json")) {
            c->json = 1;
            used = 0;
        } else if (!strcmp(a, "--quiet")) {
            c->quiet = 1;
            used = 0;
        } else if (!strcmp(a, "--calib")) {
            c->calib_file = v;
        } else if (!strcmp(a, "--csv")) {
            c->csv = v;
        } else if (!strcmp(a, "--overlay")) {
            c->overlay = v;
        } else if (!strcmp(a, "--save-calib")) {
            c->save_calib = v;
        } else if (!strcmp(a, "--shear-csv")) {
            c->shear_csv = v;
        } else if (!strcmp(a, "--depth-scene")) {
            c->depth_scene = v;
        } else if (!strcmp(a, "--depth-set")) {
            if (v && c->n_depth_sets >= TRACK_MAX_DEPTH_SETS) {
                fprintf(stderr, "ribbonctl track: more than %d --depth-set overrides\n", TRACK_MAX_DEPTH_SETS);
                return -1;
            }
            if (v) c->depth_sets[c->n_depth_sets++] = v;
        } else if (!strcmp(a, "--px-per-mm")) {
            if (parse_num(a, v, &c->px_per_mm) || c->px_per_mm <= 0)
                return -1;
        } else if (!strcmp(a, "--clamp-spacing-mm")) {
            if (parse_num(a, v, &c->spacing_mm) || c->spacing_mm <= 0)
                return -1;
        } else if (!strcmp(a, "--camera-distance-mm")) {
            if (parse_num(a, v, &c->distance_mm) || c->distance_mm <= 0)
                return -1;
        } else if (!strcmp(a, "--camera-tilt-rad")) {
            if (parse_num(a, v, &c->tilt_rad) || fabs(c->tilt_rad) > 1.2)
                return -1;
            c->have_tilt = 1;
        } else if (!strcmp(a, "--threads") || !strcmp(a, "--refresh-frames")) {
            double x = 0;
            const int th = !strcmp(a, "--threads");
            if (parse_num(a, v, &x) || x != floor(x) || x < 0 || x > (th ? 64 : 100000)) {
                fprintf(stderr, "ribbonctl track: %s needs a whole number from 0 to %d\n", a, th ? 64 : 100000);
                return -1;
            }
            if (th)
                c->threads = (int)x;
            else
                c->tp.refresh_frames = (int)x;
        } else if (!strcmp(a, "--length-mm")) {
            if (parse_num(a, v, &c->tp.length_mm) || c->tp.length_mm <= 0)
                return -1;
        } else if (!strcmp(a, "--clamp-left")) {
            if (parse_point(a, v, c->left))
                return -1;
            c->have_left = 1;
        } else if (!strcmp(a, "--clamp-right")) {
            if (parse_point(a, v, c->right))
                return -1;
            c->have_right = 1;
        } else if (!strcmp(a, "--polarity")) {
            if (v && !strcmp(v, "auto"))
                c->tp.polarity = VIS_POLARITY_AUTO;
            else if (v && !strcmp(v, "dark"))
                c->tp.polarity = VIS_POLARITY_DARK;
            else if (v && !strcmp(v, "light"))
                c->tp.polarity = VIS_POLARITY_LIGHT;
            else {
                fprintf(stderr, "ribbonctl track: --polarity needs auto, dark or light\n");
                return -1;
            }
        } else if (a[0] == '-' && a[1] == '-') {
            fprintf(stderr, "ribbonctl track: unknown option '%s'\n", a);
            return -1;
        } else if (!c->video) {
            c->video = a;
            used = 0;
        } else {
            fprintf(stderr, "ribbonctl track: unexpected argument '%s'\n", a);
            return -1;
        }
        if (used) {
            if (!v) {
                fprintf(stderr, "ribbonctl track: %s needs a value\n", a);
                return -1;
            }
            i++;
        }
    }
    if (!c->video) {
        fprintf(stderr, "ribbonctl track: no VIDEO given\n");
        return -1;
    }
    const int explicit_scale = c->px_per_mm > 0 || c->spacing_mm > 0;
    if (c->calib_file && (explicit_scale || c->have_left || c->have_right)) {
        fprintf(stderr, "ribbonctl track: --calib excludes --px-per-mm/--clamp-*\n");
        return -1;
    }
    if (c->have_left != c->have_right) {
        fprintf(stderr, "ribbonctl track: give both --clamp-left and --clamp-right, or neither "
                        "(found in the video)\n");
        return -1;
    }
    if (!c->calib_file && !explicit_scale && !(c->tp.length_mm > 0)) {
        fprintf(stderr, "ribbonctl track: need --calib FILE or a scale: --px-per-mm, "
                        "--clamp-spacing-mm or --length-mm\n");
        return -1;
    }
    if (c->px_per_mm > 0 && c->spacing_mm > 0) {
        fprintf(stderr, "ribbonctl track: give --px-per-mm or --clamp-spacing-mm, not both\n");
        return -1;
    }
    if (c->n_depth_sets > 0 && !c->depth_scene) {
        fprintf(stderr, "ribbonctl track: --depth-set needs --depth-scene\n");
        return -1;
    }
    return 0;
}

typedef struct depth_run {
    twin_depth d;
    char why[256];
    twin_status failed;
} depth_run;

static int depth_on_sample(void *user, const rod_sample *s, const rod *r)
{
    depth_run *dr = user;
    const twin_status st = twin_depth_add(&dr->d, s, r, dr->why, sizeof dr->why);
    if (st != TWIN_OK) {
        dr->failed = st;
        return 1; /* stop: the library would be silently short */
    }
    return 0;
}

/* --depth-scene: the scene predicted, its shapes kept in `dr` (c->depth points into it). 0, or 1
 * after saying why. */
static int depth_predict(track_cli *c, depth_run *dr)
{
    rod_scene sc;
    cfg_error ce;
    if (cfg_scene_load(c->depth_scene, c->depth_sets, c->n_depth_sets, &sc, &ce) != CFG_OK) {
        char buf[1200];
        fprintf(stderr, "ribbonctl track: --depth-scene: %s\n", cfg_error_format(&ce, buf, sizeof buf));
        return 1;
    }
    if (twin_depth_init(&dr->d, &sc, dr->why, sizeof dr->why) != TWIN_OK) {
        fprintf(stderr, "ribbonctl track: --depth-scene: %s\n", dr->why);
        return 1;
    }
    if (!(c->tp.length_mm > 0))
        c->tp.length_mm = sc.length * 1000.0;
    if (!c->quiet)
        fprintf(stderr, "track: predicting %s for the depth (N = %d)...\n", c->depth_scene, sc.nodes);
    rod_predict_opts o = rod_predict_opts_default();
    o.adaptive = 1;
    o.post_snap_time = 2.0;
    o.on_sample = depth_on_sample;
    o.user = dr;
    rod_prediction p;
    char err[256] = "";
    const rod_status rs = rod_predict(&sc, &o, &p, err, sizeof err);
    if (dr->failed != TWIN_OK) {
        fprintf(stderr, "ribbonctl track: --depth-scene: %s\n", dr->why);
        return 1;
    }
    if (rs != ROD_OK) {
        fprintf(stderr, "ribbonctl track: --depth-scene: the prediction failed: %s\n", err);
        return 1;
    }
    c->depth = twin_depth_library(&dr->d);
    if (c->depth.n_shapes == 0) {
        fprintf(stderr, "ribbonctl track: --depth-scene: the prediction has no sheared shape to take a depth from\n");
        return 1;
    }
    if (!c->quiet)
        fprintf(stderr, "track: depth from %zu predicted shapes (%s, %.1f s)%s\n", c->depth.n_shapes,
                p.snapped ? "snapped" : "no snap", p.wall_s,
                dr->d.full ? "; the shapes past the cap were left out" : "");
    return 0;
}

/* Shear positions per frame, from "frame,shear_mm" lines; dense array indexed by frame. */
typedef struct shear_table {
    double *mm;
    size_t n;
} shear_table;

static int shear_load(const char *path, shear_table *t)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "ribbonctl track: cannot read %s\n", path);
        return -1;
    }
    char line[256];
    int lineno = 0;
    while (fgets(line, sizeof line, f) && lineno < TRACK_MAX_FRAMES) {
        lineno++;
        char *end;
        const long fr = strtol(line, &end, 10);
        if (end == line) {
            if (lineno == 1)
                continue; /* header */
            fprintf(stderr, "ribbonctl track: %s:%d: expected frame,shear_mm\n", path, lineno);
            fclose(f);
            return -1;
        }
        char *w = end + (*end == ',');
        const double mm = cfg_number_strtod(w, &end);
        if (end == w || fr < 0 || fr >= TRACK_MAX_FRAMES || !isfinite(mm)) {
            fprintf(stderr, "ribbonctl track: %s:%d: expected frame,shear_mm\n", path, lineno);
            fclose(f);
            return -1;
        }
        if ((size_t)fr >= t->n) {
            const size_t n = (size_t)fr + 1;
            double *m = realloc(t->mm, n * sizeof *m);
            if (!m) {
                fclose(f);
                return -1;
            }
            for (size_t k = t->n; k < n; k++)
                m[k] = NAN;
            t->mm = m;
            t->n = n;
        }
        t->mm[fr] = mm;
    }
    fclose(f);
    double last = 0.0; /* fill gaps with the last value given */
    for (size_t k = 0; k < t->n; k++) {
        if (isnan(t->mm[k]))
            t->mm[k] = last;
        last = t->mm[k];
    }
    return 0;
}

static double shear_at(const shear_table *t, size_t frame)
{
    if (!t->n)
        return 0.0;
    return frame < t->n ? t->mm[frame] : t->mm[t->n - 1];
}

static const char *reason_id(vis_reason r)
{
    switch (r) {
    case VIS_REASON_NONE: return "ok";
    case VIS_REASON_UNREADABLE: return "unreadable";
    case VIS_REASON_DARK: return "dark";
    case VIS_REASON_SATURATED: return "saturated";
    case VIS_REASON_CLAMP_NOT_FOUND: return "clamp_not_found";
    case VIS_REASON_LOST: return "lost";
    case VIS_REASON_OCCLUDED: return "occluded";
    case VIS_REASON_NOISE: return "noise";
    case VIS_REASON_NO_RIBBON: return "no_ribbon";
    }
    return "unknown";
}

static void progress(size_t i, int total, int final)
{
    if (total > 0) {
        const int w = 40, done = (int)((double)(i > (size_t)total ? (size_t)total : i) * w / total);
        fprintf(stderr, "\rtrack [%.*s%*s] %zu/%d", done, "########################################",
                w - done, "", i, total);
    } else {
        fprintf(stderr, "\rtrack %zu frames", i);
    }
    if (final)
        fputc('\n', stderr);
    fflush(stderr);
}

/* Clamp points known: the scale from the spacing or --px-per-mm, or (--length-mm alone) a provisional
 * 1 px/mm until the first tracked frame; the camera's distance and pitch once the scale is real. */
static vis_status cal_complete(const track_cli *c, track_cal *tc, const double left[2],
                               const double right[2], vis_error *err)
{
    vis_calib *cal = &tc->cal;
    if (c->spacing_mm > 0) {
        if (vis_calib_from_clamps(cal, left, right, c->spacing_mm, err) != VIS_OK)
            return err->code;
    } else {
        memcpy(cal->clamp_left_px, left, sizeof cal->clamp_left_px);
        memcpy(cal->clamp_right_px, right, sizeof cal->clamp_right_px);
        cal->px_per_mm = c->px_per_mm > 0 ? c->px_per_mm : 1.0;
        tc->scale_pending = !(c->px_per_mm > 0);
    }
    if (!tc->scale_pending) {
        if (c->distance_mm > 0)
            cal->camera_distance_mm = c->distance_mm;
        if (c->have_tilt)
            cal->camera_tilt_rad = c->tilt_rad;
    }
    if (vis_calib_check(cal, err) != VIS_OK)
        return err->code;
    tc->have_clamps = 1;
    return VIS_OK;
}

/* A tracker for the calibration as it stands (in pixels, l measured, while the scale is pending). */
static vis_tracker *tracker_for(const track_cli *c, const track_cal *tc, vis_tracker *old, vis_error *err)
{
    vis_tracker_free(old);
    vis_track_params tp = c->tp;
    if (tc->scale_pending)
        tp.length_mm = 0.0;
    vis_tracker *t = vis_tracker_create(&tp, &tc->cal, err);
    if (t && c->depth.n_shapes > 0 && vis_tracker_set_depth_library(t, &c->depth, err) != VIS_OK) {
        vis_tracker_free(t);
        return NULL;
    }
    return t;
}

static json_t *json_point(const double p[2])
{
    json_t *a = json_array();
    json_array_append_new(a, json_real(p[0]));
    json_array_append_new(a, json_real(p[1]));
    return a;
}

/* Everything one run of the frame loop holds: outputs, the per-frame series, the first failure. */
typedef struct track_run {
    int rc;
    FILE *csv;
    vis_source *src;
    vis_tracker *trk;
    vis_frame *frame, *over;
    vis_video_writer *ov;
    double *dz;
    unsigned char *valid;
    size_t n, cap, tracked;
    double qsum;
    int damaged;
    long clamps_frame; /* frame where the clamps were found, -1 when given */
    char failure[400];
    /* Once the calibration is complete: the tracker's work on every core. */
    vis_track_pipe *pipe;
    double *t_ring;    /* the times of the frames in the pipe, by frame number modulo its capacity */
    double *uv;        /* a popped frame's centreline */
    vis_frame *popped; /* a popped frame (for the overlay) */
} track_run;


/* The calibration from --calib, or from the given parts (clamp points may still be found later);
 * saved now when already complete. Returns 0, or the exit status after printing the reason. */
static int track_calibration(const track_cli *c, track_cal *tc)
{
    vis_error err;
    memset(tc, 0, sizeof *tc);
    tc->cal = vis_calib_default();
    if (c->calib_file) {
        if (vis_calib_load(&tc->cal, c->calib_file, &err) != VIS_OK) {
            fprintf(stderr, "ribbonctl track: %s\n", err.message);
            return 1;
        }
        tc->have_clamps = 1;
    } else if (c->have_left && cal_complete(c, tc, c->left, c->right, &err) != VIS_OK) {
        fprintf(stderr, "ribbonctl track: %s\n", err.message);
        return 2;
    }
    if (tc->have_clamps && !tc->scale_pending && c->save_calib &&
        vis_calib_save(&tc->cal, c->save_calib, &err) != VIS_OK) {
        fprintf(stderr, "ribbonctl track: %s\n", err.message);
        return 1;
    }
    return 0;
}

/* The source, the tracker (when the clamps are known), the frames and the CSV. 0, or 1 with
 * r->failure set. */
static int track_open(const track_cli *c, const track_cal *tc, track_run *r)
{
    vis_error err;
    /* A name with a printf conversion is an image sequence ("dir/frame_%04d.png", from 0). */
    r->src = strchr(c->video, '%') ? vis_source_open_images(c->video, 0, &err)
                                   : vis_source_open_video_prefetch(c->video, &err);
    if (!r->src) {
        snprintf(r->failure, sizeof r->failure, "%s", err.message);
        return 1;
    }
    if (tc->have_clamps)
        r->trk = tracker_for(c, tc, NULL, &err);
    r->frame = vis_frame_alloc(8, 8, 1, &err);
    r->over = vis_frame_alloc(8, 8, 3, &err);
    if ((tc->have_clamps && !r->trk) || !r->frame || !r->over) {
        snprintf(r->failure, sizeof r->failure, "%s", err.message);
        return 1;
    }
    r->uv = malloc(2 * TRACK_UV_MAX * sizeof *r->uv);
    if (!r->uv) {
        snprintf(r->failure, sizeof r->failure, "out of memory");
        return 1;
    }
    if (c->csv) {
        r->csv = fopen(c->csv, "w");
        if (!r->csv) {
            snprintf(r->failure, sizeof r->failure, "cannot write %s", c->csv);
            return 1;
        }
        fprintf(r->csv, "frame,t,dz,a,quality,reason\n");
    }
    return 0;
}

/* Until the clamps are known: look for them in frame i (at zero shear only) and, once found,
 * make the tracker. 0 (found or not yet), or 1 with r->failure set. */
static int track_find_clamps(const track_cli *c, track_cal *tc, track_run *r, size_t i, double sh,
                             int show)
{
    vis_error err;
    double lp[2], rp[2], q = 0;
    const vis_status fs = sh != 0.0 ? VIS_ERR_NOT_FOUND
                                    : vis_find_clamps(r->frame, &c->tp, lp, rp, &q, &err);
    if (sh != 0.0)
        snprintf(tc->why, sizeof tc->why, "frame %zu: clamps are looked for at zero shear only", i);
    else if (fs == VIS_ERR_NOT_FOUND)
        snprintf(tc->why, sizeof tc->why, "frame %zu: %s", i, err.message);
    else if (fs != VIS_OK || cal_complete(c, tc, lp, rp, &err) != VIS_OK ||
             !(r->trk = tracker_for(c, tc, NULL, &err))) {
        snprintf(r->failure, sizeof r->failure, "frame %zu: clamps: %s", i, err.message);
        return 1;
    } else {
        r->clamps_frame = (long)i;
        if (show)
            fprintf(stderr, "\rtrack: clamps found in frame %zu at (%.2f, %.2f) and (%.2f, %.2f) "
                            "px, quality %.2f\n", i, lp[0], lp[1], rp[0], rp[1], q);
        if (!tc->scale_pending && c->save_calib &&
            vis_calib_save(&tc->cal, c->save_calib, &err) != VIS_OK) {
            snprintf(r->failure, sizeof r->failure, "%s", err.message);
            return 1;
        }
    }
    return 0;
}

/* First tracked frame in pixels: the scale is its length over l; measure it again. 0, or 1 with
 * r->failure set. */
static int track_scale_from_length(const track_cli *c, track_cal *tc, track_run *r, size_t i,
                                   double sh, vis_measure *m, int show)
{
    vis_error err;
    tc->cal.px_per_mm = m->length_mm / c->tp.length_mm;
    tc->scale_pending = 0;
    if (c->distance_mm > 0)
        tc->cal.camera_distance_mm = c->distance_mm;
    if (c->have_tilt)
        tc->cal.camera_tilt_rad = c->tilt_rad;
    if (vis_calib_check(&tc->cal, &err) != VIS_OK || !(r->trk = tracker_for(c, tc, r->trk, &err)) ||
        vis_tracker_process(r->trk, r->frame, sh, m, &err) != VIS_OK) {
        snprintf(r->failure, sizeof r->failure, "frame %zu: scale from the length: %s", i, err.message);
        return 1;
    }
    if (show)
        fprintf(stderr, "\rtrack: scale %.4f px/mm from the ribbon's length in frame %zu\n",
                tc->cal.px_per_mm, i);
    if (c->save_calib && vis_calib_save(&tc->cal, c->save_calib, &err) != VIS_OK) {
        snprintf(r->failure, sizeof r->failure, "%s", err.message);
        return 1;
    }
    return 0;
}

/* Keep frame i's measurement in the series (growing it) and write its CSV row. 0, or 1 with
 * r->failure set. */
static int track_record(track_run *r, size_t i, double t, const vis_measure *m)
{
    if (r->n == r->cap) {
        const size_t nc = r->cap ? 2 * r->cap : 1024;
        double *d2 = realloc(r->dz, nc * sizeof *d2);
        if (d2)
            r->dz = d2;
        unsigned char *v2 = realloc(r->valid, nc);
        if (v2)
            r->valid = v2;
        if (!d2 || !v2) {
            snprintf(r->failure, sizeof r->failure, "out of memory at frame %zu", i);
            return 1;
        }
        r->cap = nc;
    }
    const int ok = m->reason == VIS_REASON_NONE;
    r->dz[r->n] = ok ? m->dz : 0.0;
    r->valid[r->n] = (unsigned char)ok;
    r->n++;
    if (ok) {
        r->tracked++;
        r->qsum += m->quality;
    }
    if (r->csv) {
        if (ok)
            fprintf(r->csv, "%zu,%.6f,%.8f,%.8f,%.4f,%s\n", i, t, m->dz, m->a, m->quality,
                    reason_id(m->reason));
        else
            fprintf(r->csv, "%zu,%.6f,,,%.4f,%s\n", i, t, m->quality, reason_id(m->reason));
    }
    return 0;
}

/* r->over (a frame with its measurement drawn on it) appended to the overlay video (opened at the
 * first frame). 0, or 1 with r->failure set. */
static int track_overlay_write(const track_cli *c, track_run *r, double fps)
{
    vis_error err;
    if (!r->ov) {
        r->ov = vis_video_writer_open(c->overlay, vis_frame_width(r->over), vis_frame_height(r->over),
                                      3, fps > 0 ? fps : 25.0, &err);
        if (!r->ov) {
            snprintf(r->failure, sizeof r->failure, "%s", err.message);
            return 1;
        }
    }
    if (vis_video_writer_write(r->ov, r->over, &err) != VIS_OK) {
        snprintf(r->failure, sizeof r->failure, "overlay: %s", err.message);
        return 1;
    }
    return 0;
}

/* Frame i (its time t) measured: recorded, drawn on the overlay (with the centreline uv, n pairs),
 * the progress shown. 0, or 1 with r->failure set. */
static int track_done(const track_cli *c, track_run *r, size_t i, double t, const vis_frame *frame,
                      const double *uv, size_t n, const vis_measure *m, double fps, int total)
{
    if (track_record(r, i, t, m))
        return 1;
    if (c->overlay) {
        vis_error err;
        if (vis_overlay_draw_curve(frame, uv, n, m, (int)i, r->over, &err) != VIS_OK) {
            snprintf(r->failure, sizeof r->failure, "overlay: %s", err.message);
            return 1;
        }
        if (track_overlay_write(c, r, fps))
            return 1;
    }
    if (!c->quiet && r->n % 10 == 0)
        progress(r->n, total, 0);
    return 0;
}

/* The oldest frame in the pipe, when done (waiting for it when `wait`). 1 when one was taken, 0
 * when none, -1 with r->failure set. */
static int track_pop(const track_cli *c, track_run *r, int wait, double fps, int total)
{
    vis_error err;
    vis_measure m;
    size_t n = 0;
    const vis_status s = vis_track_pipe_pop(r->pipe, wait, &m, r->uv, TRACK_UV_MAX, &n, r->popped, &err);
    if (s == VIS_ERR_NOT_FOUND || s == VIS_ERR_END)
        return 0;
    const size_t i = r->n;
    if (s != VIS_OK) {
        snprintf(r->failure, sizeof r->failure, "frame %zu: %s", i, err.message);
        r->damaged = 0; /* the run ends here, before any damage read further on */
        return -1;
    }
    const size_t cap = vis_track_pipe_capacity(r->pipe);
    if (track_done(c, r, i, r->t_ring[i % cap], r->popped, r->uv, n < TRACK_UV_MAX ? n : TRACK_UV_MAX, &m, fps,
                   total))
        return -1;
    return 1;
}

/* The tracker is complete (clamps and scale known): from the next frame on it works through the
 * pipe, unless --threads 1. 0, or 1 with r->failure set. */
static int track_start_pipe(const track_cli *c, track_run *r)
{
    if (c->threads == 1 || r->pipe)
        return 0;
    vis_error err;
    r->pipe = vis_track_pipe_create(r->trk, c->threads, &err);
    const size_t cap = r->pipe ? vis_track_pipe_capacity(r->pipe) : 0;
    r->t_ring = r->pipe ? calloc(cap, sizeof *r->t_ring) : NULL;
    r->popped = r->pipe ? vis_frame_alloc(8, 8, 1, &err) : NULL;
    if (!r->pipe || !r->t_ring || !r->popped) {
        snprintf(r->failure, sizeof r->failure, "tracking on every core: %s", r->pipe ? "out of memory" : err.message);
        return 1;
    }
    return 0;
}

/* Every frame of the source, up to the end, the damage or the first failure. */
static void track_frames(const track_cli *c, track_cal *tc, const shear_table *shear, track_run *r)
{
    vis_error err;
    const int total = vis_source_frame_count(r->src);
    const int show = !c->quiet;
    const double fps = vis_source_fps(r->src);
    for (size_t i = 0; i < TRACK_MAX_FRAMES; i++) {
        double t = 0.0;
        if (r->pipe && vis_track_pipe_held(r->pipe) >= vis_track_pipe_capacity(r->pipe) &&
            track_pop(c, r, 1, fps, total) < 0) {
            r->rc = 1;
            break;
        }
        const vis_status st = vis_source_read(r->src, r->frame, &t, &err);
        if (st == VIS_ERR_END)
            break;
        if (st != VIS_OK) {
            snprintf(r->failure, sizeof r->failure, "%s", err.message);
            r->damaged = 1;
            r->rc = 1;
            break;
        }
        const double sh = shear_at(shear, i);
        if (r->pipe) {
            r->t_ring[i % vis_track_pipe_capacity(r->pipe)] = t;
            if (vis_track_pipe_push(r->pipe, r->frame, sh, 0, &err) != VIS_OK) {
                snprintf(r->failure, sizeof r->failure, "frame %zu: %s", i, err.message);
                r->rc = 1;
                break;
            }
            int got;
            while ((got = track_pop(c, r, 0, fps, total)) > 0) {
            }
            if (got < 0) {
                r->rc = 1;
                break;
            }
            continue;
        }
        vis_measure m;
        memset(&m, 0, sizeof m);
        m.reason = VIS_REASON_CLAMP_NOT_FOUND;
        if (!tc->have_clamps && track_find_clamps(c, tc, r, i, sh, show)) {
            r->rc = 1;
            break;
        }
        if (r->trk && vis_tracker_process(r->trk, r->frame, sh, &m, &err) != VIS_OK) {
            snprintf(r->failure, sizeof r->failure, "frame %zu: %s", i, err.message);
            r->rc = 1;
            break;
        }
        if (r->trk && tc->scale_pending && m.reason == VIS_REASON_NONE &&
            track_scale_from_length(c, tc, r, i, sh, &m, show)) {
            r->rc = 1;
            break;
        }
        const size_t n = r->trk && c->overlay ? vis_tracker_curve(r->trk, r->uv, TRACK_UV_MAX) : 0;
        if (track_done(c, r, i, t, r->frame, r->uv, n < TRACK_UV_MAX ? n : TRACK_UV_MAX, &m, fps, total) ||
            (r->trk && !tc->scale_pending && track_start_pipe(c, r))) {
            r->rc = 1;
            break;
        }
    }
    /* The frames still in the pipe were read before the end or the damage: they are kept, up to a
     * frame the tracker fails on (after any other failure, nothing more is written). */
    if (r->pipe && (!r->rc || r->damaged)) {
        int got;
        while ((got = track_pop(c, r, 1, fps, total)) > 0) {
        }
        if (got < 0)
            r->rc = 1;
    }
    if (show)
        progress(r->n, total, 1);
}

/* The failures only the whole run shows, the CSV closed, and the summary (text or --json). */
static void track_report(const track_cli *c, const track_cal *tc, track_run *r)
{
    if (!r->failure[0] && r->src && r->n > 0 && !tc->have_clamps) {
        snprintf(r->failure, sizeof r->failure, "no clamp pair found in any frame (last: %s)", tc->why);
        r->rc = 1;
    } else if (!r->failure[0] && r->src && r->n > 0 && tc->scale_pending) {
        snprintf(r->failure, sizeof r->failure, "no frame was tracked, so the scale from --length-mm is "
                                                "unknown%s", c->save_calib ? " (no calibration saved)" : "");
        r->rc = 1;
    }
    const int snap = r->n ? vis_snap_find(r->dz, r->valid, r->n, 0.02, 0.3) : -1;
    if (r->csv && fclose(r->csv) != 0 && !r->rc) {
        snprintf(r->failure, sizeof r->failure, "cannot write %s", c->csv);
        r->rc = 1;
    }
    r->csv = NULL;
    vis_video_writer_close(r->ov);
    r->ov = NULL;
    if (r->failure[0])
        fprintf(stderr, "ribbonctl track: %s\n", r->failure);
    const double mean_q = r->tracked ? r->qsum / (double)r->tracked : 0.0;
    if (c->json) {
        json_t *o = json_object();
        json_object_set_new(o, "video", json_string(c->video));
        json_object_set_new(o, "frames", json_integer((json_int_t)r->n));
        json_object_set_new(o, "tracked", json_integer((json_int_t)r->tracked));
        json_object_set_new(o, "mean_quality", json_real(mean_q));
        json_object_set_new(o, "snap_frame", snap >= 0 ? json_integer(snap) : json_null());
        const int cal_ok = tc->have_clamps && !tc->scale_pending;
        json_object_set_new(o, "px_per_mm", cal_ok ? json_real(tc->cal.px_per_mm) : json_null());
        json_object_set_new(o, "clamp_left", tc->have_clamps ? json_point(tc->cal.clamp_left_px) : json_null());
        json_object_set_new(o, "clamp_right", tc->have_clamps ? json_point(tc->cal.clamp_right_px) : json_null());
        json_object_set_new(o, "clamps_frame", r->clamps_frame >= 0 ? json_integer(r->clamps_frame) : json_null());
        json_object_set_new(o, "depth_shapes",
                            c->depth.n_shapes ? json_integer((json_int_t)c->depth.n_shapes) : json_null());
        json_object_set_new(o, "tracking_threads", json_integer(r->pipe ? vis_track_pipe_workers(r->pipe) : 1));
        json_object_set_new(o, "damaged", json_boolean(r->damaged));
        json_object_set_new(o, "error", r->failure[0] ? json_string(r->failure) : json_null());
        char *s = json_dumps(o, JSON_COMPACT);
        printf("%s\n", s ? s : "{}");
        free(s);
        json_decref(o);
    } else if (r->src) {
        printf("frames %zu, tracked %zu, mean quality %.3f, snap frame ", r->n, r->tracked, mean_q);
        if (snap >= 0)
            printf("%d\n", snap);
        else
            printf("none\n");
    }
}

static void track_run_free(track_run *r)
{
    vis_track_pipe_free(r->pipe);
    free(r->t_ring);
    free(r->uv);
    vis_frame_free(r->popped);
    free(r->dz);
    free(r->valid);
    vis_frame_free(r->frame);
    vis_frame_free(r->over);
    vis_tracker_free(r->trk);
    vis_source_close(r->src);
}

int ctl_track_main(int argc, char **argv)
{
    track_cli c;
    const int pa = parse_args(argc, argv, &c);
    if (pa > 0)
        return 0;
    if (pa < 0) {
        usage(stderr);
        return 2;
    }
    depth_run dr;
    memset(&dr, 0, sizeof dr);
    if (c.depth_scene && depth_predict(&c, &dr)) {
        twin_depth_release(&dr.d);
        return 1;
    }
    track_cal tc;
    const int cal_rc = track_calibration(&c, &tc);
    if (cal_rc) {
        twin_depth_release(&dr.d);
        return cal_rc;
    }
    shear_table shear = {NULL, 0};
    if (c.shear_csv && shear_load(c.shear_csv, &shear)) {
        free(shear.mm);
        twin_depth_release(&dr.d);
        return 1;
    }
    track_run r;
    memset(&r, 0, sizeof r);
    r.clamps_frame = -1;
    if (track_open(&c, &tc, &r))
        r.rc = 1;
    else
        track_frames(&c, &tc, &shear, &r);
    track_report(&c, &tc, &r);
    free(shear.mm);
    track_run_free(&r);
    twin_depth_release(&dr.d);
    return r.rc;
}
