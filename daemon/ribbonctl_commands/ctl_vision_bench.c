/* ctl_vision_bench.c: `ribbonctl vision-bench`: speed of the vision module, one JSON line.
 *
 *   ribbonctl vision-bench [--width W --height H] [--frames N] [--refresh K] [--dir DIR]
 *
 * Renders N frames (default 200) of a ribbon arch (a cosine arch between clamps 160 mm apart, 5 mm
 * wide and 1 mm thick, about 5 px in the image, with a slowly growing asymmetric mode) at W x H (default 1280 x 720), writes them to an
 * FFV1 file in DIR (default TMPDIR or /tmp, removed afterwards), then times, from one calling
 * thread:
 *   track_fps         the tracker alone on frames held in memory,
 *   decode_fps        decoding the FFV1 file alone (vis_source_read: decode, then grey),
 *   decode_track_fps  decoding the FFV1 file and tracking every frame.
 * Each phase also gets *_cpu_fps, frames per second of process CPU time (all threads): OpenCV 4.6's
 * FFmpeg reader decodes with as many libavcodec threads as the machine has cores and has no option
 * to change that, so the wall-clock decode figures are not one-thread figures; the CPU figures are
 * what one thread could do at best. decode_threads counts the threads that took at least a tenth
 * of the CPU time while decoding (from /proc/self/task; -1 where that cannot be read).
 * Issue 5's targets (one thread): track_fps >= 500, decode_track_fps >= 150. Rendering is not
 * timed. Then (issue 14) one line per recording format ("bench":"vision_video", FFV1 .mkv and raw
 * Y800 .avi of the same frames): decode + track through vis_track_video serially on one pinned
 * CPU and on every core (stretches of K = --refresh frames, the tracker's refresh_frames, default
 * 100, tracked in parallel: raw Y800 read by each worker, FFV1 decoded on one thread into
 * vis_track_pipe), the speed-up, whether every frame's result is identical, the CPU ms of decoding
 * and of tracking apart in the serial run and the bound overlapping them alone would give, the CPU
 * ms a frame of the all-cores run (all threads), the load average; and
 * one line for the tracker alone on a 1280 x 256 ROI on one pinned CPU ("bench":"vision_roi",
 * target 1000 fps). docs/vision-acquisition-and-replay-speed.md has the measured figures. */
#define _GNU_SOURCE /* sched_setaffinity: the one-core figures run pinned to one CPU */
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "ctl.h"
#include "vision.h"

#define BENCH_MAX_FRAMES 5000
#define BENCH_PTS 301
#define BENCH_MAX_TASKS 256

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Process CPU time (user + system, every thread), seconds. */
static double cpu_s(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0)
        return 0.0;
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

/* CPU ticks (utime + stime) of each thread of this process. */
typedef struct task_ticks {
    long id[BENCH_MAX_TASKS];
    unsigned long ticks[BENCH_MAX_TASKS];
    int n;  /* -1 when /proc cannot be read */
} task_ticks;

static void task_ticks_read(task_ticks *t)
{
    t->n = 0;
    DIR *d = opendir("/proc/self/task");
    if (!d) {
        t->n = -1;
        return;
    }
    struct dirent *e;
    while ((e = readdir(d)) && t->n < BENCH_MAX_TASKS) {
        if (e->d_name[0] == '.')
            continue;
        char path[300], buf[1024];
        snprintf(path, sizeof path, "/proc/self/task/%s/stat", e->d_name);
        FILE *f = fopen(path, "r");
        if (!f)
            continue;
        const size_t n = fread(buf, 1, sizeof buf - 1, f);
        fclose(f);
        buf[n] = '\0';
        /* After the command name's closing parenthesis: state (field 3) ... utime (14), stime (15). */
        const char *p = strrchr(buf, ')');
        unsigned long ut = 0, st = 0;
        if (!p || sscanf(p + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lu %lu", &ut, &st) != 2)
            continue;
        t->id[t->n] = atol(e->d_name);
        t->ticks[t->n] = ut + st;
        t->n++;
    }
    closedir(d);
}

/* Threads that took at least a tenth of the CPU ticks between two readings, or -1. */
static int busy_threads(const task_ticks *a, const task_ticks *b)
{
    if (a->n <= 0 || b->n <= 0)
        return -1;
    unsigned long total = 0, delta[BENCH_MAX_TASKS];
    for (int j = 0; j < b->n; j++) {
        unsigned long before = 0;
        for (int i = 0; i < a->n; i++)
            if (a->id[i] == b->id[j])
                before = a->ticks[i];
        delta[j] = b->ticks[j] >= before ? b->ticks[j] - before : 0;
        total += delta[j];
    }
    int busy = 0;
    for (int j = 0; j < b->n; j++)
        busy += total > 0 && 10 * delta[j] >= total;
    return busy;
}

/* Cosine arch with an antisymmetric mode of relative amplitude `asym`, n points (not arc-length
 * spaced: the renderer and tracker do not need it), unit normals in the x-z plane. */
static void bench_shape(double *pos, double *nrm, double asym)
{
    const double X = 0.16, R = 0.055;
    for (int i = 0; i < BENCH_PTS; i++) {
        const double xi = (double)i / (BENCH_PTS - 1), c = cos(2 * M_PI * xi), sn = sin(2 * M_PI * xi);
        pos[3 * i] = X * xi;
        pos[3 * i + 1] = 0.0;
        pos[3 * i + 2] = R * ((1 - c) / 2 + asym * sn * (1 - c) / 2);
        const double dz = R * (M_PI * sn + asym * M_PI * (c * (1 - c) + sn * sn)) / X;
        const double l = sqrt(1 + dz * dz);
        nrm[3 * i] = -dz / l;
        nrm[3 * i + 1] = 0.0;
        nrm[3 * i + 2] = 1.0 / l;
    }
}

/* Pin the calling thread (and the threads it creates from now on) to its first allowed CPU;
 * `saved` gets the old mask for unpin. Returns 0 when pinned. */
static int pin_one_core(cpu_set_t *saved)
{
    if (sched_getaffinity(0, sizeof *saved, saved) != 0)
        return -1;
    for (int c = 0; c < CPU_SETSIZE; c++)
        if (CPU_ISSET(c, saved)) {
            cpu_set_t one;
            CPU_ZERO(&one);
            CPU_SET(c, &one);
            return sched_setaffinity(0, sizeof one, &one);
        }
    return -1;
}

static void unpin(const cpu_set_t *saved) { sched_setaffinity(0, sizeof *saved, saved); }

/* Decode + track of one recording (issue 14): the serial loop on one pinned core, then
 * vis_track_video on every core; one JSON line with both rates, the speed-up and whether every
 * frame's result is identical. */
static int bench_video_format(const char *path, const char *format, vis_frame **mem, int frames, int w, int h,
                              const vis_calib *cal, const vis_track_params *tp, vis_error *err)
{
    vis_video_writer *vw = strcmp(format, "y800") == 0 ? vis_video_writer_open_y800(path, w, h, 30.0, err)
                                                        : vis_video_writer_open(path, w, h, 1, 30.0, err);
    if (!vw)
        return 1;
    for (int i = 0; i < frames; i++)
        if (vis_video_writer_write(vw, mem[i], err) != VIS_OK) {
            vis_video_writer_close(vw);
            return 1;
        }
    vis_video_writer_close(vw);
    vis_measure *a = calloc((size_t)frames, sizeof *a), *b = calloc((size_t)frames, sizeof *b);
    vis_tracker *t1 = vis_tracker_create(tp, cal, err), *t2 = vis_tracker_create(tp, cal, err);
    int rc = 1;
    size_t na = 0, nb = 0;
    cpu_set_t saved;
    if (!a || !b || !t1 || !t2)
        goto out;
    const int pinned = pin_one_core(&saved) == 0;
    /* The serial loop by hand, pinned, with the process CPU time of decoding (libavcodec's threads
     * included) and of tracking apart: on a loaded machine the wall clock says little, and
     * max(decode, track) / (decode + track) is what overlapping them can give at best. */
    double dec_cpu = 0, trk_cpu = 0;
    double t0 = now_s();
    vis_source *src = vis_source_open_video(path, err);
    vis_frame *f = vis_frame_alloc(8, 8, 1, err);
    vis_status sa = src && f ? VIS_OK : VIS_ERR_IO;
    for (size_t i = 0; sa == VIS_OK && i < (size_t)frames; i++) {
        const double c0 = cpu_s();
        sa = vis_source_read(src, f, NULL, err);
        const double c1 = cpu_s();
        dec_cpu += c1 - c0;
        if (sa == VIS_ERR_END) {
            sa = VIS_OK;
            break;
        }
        if (sa == VIS_OK)
            sa = vis_tracker_process(t1, f, 0.0, &a[i], err);
        trk_cpu += cpu_s() - c1;
        if (sa == VIS_OK)
            na = i + 1;
    }
    vis_source_close(src);
    vis_frame_free(f);
    const double serial_s = now_s() - t0;
    if (pinned)
        unpin(&saved);
    if (sa != VIS_OK)
        goto out;
    t0 = now_s();
    const double par_c0 = cpu_s();
    if (vis_track_video(path, t2, NULL, 0, 0, b, (size_t)frames, &nb, err) != VIS_OK)
        goto out;
    const double par_s = now_s() - t0, par_cpu = cpu_s() - par_c0;
    int identical = na == nb;
    for (size_t i = 0; identical && i < na; i++)
        identical = a[i].reason == b[i].reason && a[i].dz == b[i].dz && a[i].a == b[i].a &&
                    a[i].quality == b[i].quality && a[i].length_mm == b[i].length_mm &&
                    a[i].mid_px[0] == b[i].mid_px[0] && a[i].mid_px[1] == b[i].mid_px[1];
    const long cores = sysconf(_SC_NPROCESSORS_ONLN);
    double la[3] = {-1, -1, -1};
    if (getloadavg(la, 3) < 1)
        la[0] = -1;
    const double dms = na ? 1e3 * dec_cpu / (double)na : 0, tms = na ? 1e3 * trk_cpu / (double)na : 0;
    const double mx = dms > tms ? dms : tms;
    printf("{\"bench\":\"vision_video\",\"format\":\"%s\",\"width\":%d,\"height\":%d,\"frames\":%zu,\"refresh_frames\":%d,"
           "\"one_core_pinned\":%s,\"fps_one_core\":%.1f,\"fps_all_cores\":%.1f,\"cores\":%ld,"
           "\"speedup\":%.2f,\"identical\":%s,\"decode_cpu_ms\":%.2f,\"track_cpu_ms\":%.2f,"
           "\"fps_one_core_cpu\":%.1f,\"fps_overlap_bound_cpu\":%.1f,\"speedup_bound_cpu\":%.2f,"
           "\"all_cores_cpu_ms\":%.2f,\"load_avg\":%.1f,\"target_speedup\":1.8,\"target_fps\":150}\n",
           format, w, h, nb, tp->refresh_frames, pinned ? "true" : "false", (double)na / serial_s, (double)nb / par_s, cores,
           serial_s / par_s * (double)nb / (double)(na ? na : 1), identical ? "true" : "false", dms, tms,
           dms + tms > 0 ? 1e3 / (dms + tms) : 0.0, mx > 0 ? 1e3 / mx : 0.0, mx > 0 ? (dms + tms) / mx : 0.0,
           nb ? 1e3 * par_cpu / (double)nb : 0.0, la[0]);
    rc = 0;
out:
    free(a);
    free(b);
    vis_tracker_free(t1);
    vis_tracker_free(t2);
    remove(path);
    return rc;
}

/* The tracker alone on a 1280 x 256 region of interest (a high-speed camera's), one pinned core. */
static int bench_roi(const vis_render_params *rp0, vis_error *err)
{
    enum { RW = 1280, RH = 256, RN = 300 };
    static double pos[3 * BENCH_PTS], nrm[3 * BENCH_PTS];
    vis_shape sh = {BENCH_PTS, pos, nrm, 0.005, 0.001};
    vis_render_params rp = *rp0;
    rp.camera.width_px = RW;
    rp.camera.height_px = RH;
    if (vis_camera_fit(&rp.camera, -0.02, 0.18, -0.01, 0.03, 0.95, err) != VIS_OK)
        return 1;
    vis_renderer *r = vis_renderer_create(&rp, err);
    vis_frame *fr[8] = {0};
    vis_tracker *t = NULL;
    int rc = 1, tracked = 0;
    if (!r)
        return 1;
    for (int i = 0; i < 8; i++) {
        bench_shape(pos, nrm, 0.3 * i / 8.0);
        for (int k = 0; k < 3 * BENCH_PTS; k += 3)
            pos[k + 2] *= 0.3; /* a flat arch: 1280 x 256 frames a low ribbon */
        if (!(fr[i] = vis_frame_alloc(RW, RH, 1, err)) || vis_renderer_draw(r, &sh, fr[i], NULL, err) != VIS_OK)
            goto out;
    }
    vis_calib cal = vis_calib_default();
    const double l0[3] = {0, 0, 0}, r0[3] = {0.16, 0, 0};
    vis_camera_project(&rp.camera, l0, cal.clamp_left_px, NULL);
    vis_camera_project(&rp.camera, r0, cal.clamp_right_px, NULL);
    cal.px_per_mm = rp.camera.focal_px / rp.camera.distance_m / 1000.0;
    vis_track_params tp = vis_track_params_default();
    if (!(t = vis_tracker_create(&tp, &cal, err)))
        goto out;
    cpu_set_t saved;
    const int pinned = pin_one_core(&saved) == 0;
    vis_measure m;
    /* Frames cycle up and back through the 8 shapes: consecutive frames differ as in a video. */
    const double t0 = now_s(), c0 = cpu_s();
    for (int i = 0; i < RN; i++) {
        const int j = i % 14 < 8 ? i % 14 : 14 - i % 14;
        if (vis_tracker_process(t, fr[j], 0.0, &m, err) != VIS_OK)
            goto out;
        tracked += m.reason == VIS_REASON_NONE;
    }
    const double dt = now_s() - t0, dc = cpu_s() - c0;
    if (pinned)
        unpin(&saved);
    printf("{\"bench\":\"vision_roi\",\"width\":%d,\"height\":%d,\"frames\":%d,\"tracked\":%d,"
           "\"one_core_pinned\":%s,\"track_fps\":%.1f,\"track_cpu_fps\":%.1f,\"target_track_fps\":1000}\n",
           RW, RH, RN, tracked, pinned ? "true" : "false", RN / dt, dc > 0 ? RN / dc : 0.0);
    rc = 0;
out:
    for (int i = 0; i < 8; i++)
        vis_frame_free(fr[i]);
    vis_tracker_free(t);
    vis_renderer_free(r);
    return rc;
}

int ctl_vision_bench_main(int argc, char **argv)
{
    int w = 1280, h = 720, frames = 200, refresh = vis_track_params_default().refresh_frames;
    const char *dir = getenv("TMPDIR");
    for (int i = 1; i < argc; i++) {
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            printf("usage: ribbonctl vision-bench [--width W --height H] [--frames N] [--refresh K] [--dir DIR]\n"
                   "  One JSON line per measurement (see docs/vision-acquisition-and-replay-speed.md): the tracker\n"
                   "  and FFV1 decoding on one thread; decode + track of a W x H recording (default 1280 x 720,\n"
                   "  N frames, default 200) in FFV1 and raw Y800, on one pinned core and on every core, with the\n"
                   "  tracker refreshing every K frames (default: the tracker's, 100); the tracker on a 1280 x 256 ROI.\n");
            return 0;
        } else if (!strcmp(argv[i], "--width") && v) {
            w = atoi(v);
            i++;
        } else if (!strcmp(argv[i], "--height") && v) {
            h = atoi(v);
            i++;
        } else if (!strcmp(argv[i], "--frames") && v) {
            frames = atoi(v);
            i++;
        } else if (!strcmp(argv[i], "--refresh") && v) {
            refresh = atoi(v);
            i++;
        } else if (!strcmp(argv[i], "--dir") && v) {
            dir = v;
            i++;
        } else {
            fprintf(stderr, "ribbonctl vision-bench: unknown option '%s'\n", argv[i]);
            return 2;
        }
    }
    if (w < 64 || h < 48 || w > 8192 || h > 8192 || frames < 1 || frames > BENCH_MAX_FRAMES || refresh < 0 ||
        refresh > 100000) {
        fprintf(stderr, "ribbonctl vision-bench: need 64 <= width, 48 <= height <= 8192, 1 <= frames <= %d, "
                "0 <= refresh <= 100000\n", BENCH_MAX_FRAMES);
        return 2;
    }
    char path[1024];
    snprintf(path, sizeof path, "%s/ribbon-vision-bench-%ld.mkv", dir && dir[0] ? dir : "/tmp", (long)getpid());

    static double pos[3 * BENCH_PTS], nrm[3 * BENCH_PTS];
    vis_shape sh = {BENCH_PTS, pos, nrm, 0.005, 0.001}; /* 5 mm wide, 1 mm thick: about 5 px here */
    vis_render_params rp = vis_render_params_default();
    rp.camera.width_px = w;
    rp.camera.height_px = h;
    vis_error err;
    int rc = 1;
    vis_frame **mem = calloc((size_t)frames, sizeof *mem);
    vis_frame *f = vis_frame_alloc(8, 8, 1, &err);
    vis_renderer *r = NULL;
    vis_video_writer *vw = NULL;
    vis_tracker *t = NULL;
    vis_source *src = NULL;
    if (!mem || !f)
        goto out;
    if (vis_camera_fit(&rp.camera, -0.02, 0.18, -0.03, 0.09, 0.9, &err) != VIS_OK)
        goto out;
    r = vis_renderer_create(&rp, &err);
    vw = r ? vis_video_writer_open(path, w, h, 1, 30.0, &err) : NULL;
    if (!vw)
        goto out;
    for (int i = 0; i < frames; i++) {
        bench_shape(pos, nrm, 0.3 * i / frames);
        mem[i] = vis_frame_alloc(w, h, 1, &err);
        if (!mem[i] || vis_renderer_draw(r, &sh, mem[i], NULL, &err) != VIS_OK ||
            vis_video_writer_write(vw, mem[i], &err) != VIS_OK)
            goto out;
    }
    vis_video_writer_close(vw);
    vw = NULL;

    vis_calib cal = vis_calib_default();
    const double l0[3] = {0, 0, 0}, r0[3] = {0.16, 0, 0};
    vis_camera_project(&rp.camera, l0, cal.clamp_left_px, NULL);
    vis_camera_project(&rp.camera, r0, cal.clamp_right_px, NULL);
    cal.px_per_mm = rp.camera.focal_px / rp.camera.distance_m / 1000.0;
    vis_track_params tp = vis_track_params_default();
    tp.ribbon_max_px = 8.0;
    tp.refresh_frames = refresh;
    t = vis_tracker_create(&tp, &cal, &err);
    if (!t)
        goto out;
    vis_measure m;
    int tracked = 0;
    double t0 = now_s(), c0 = cpu_s();
    for (int i = 0; i < frames; i++) {
        if (vis_tracker_process(t, mem[i], 0.0, &m, &err) != VIS_OK)
            goto out;
        tracked += m.reason == VIS_REASON_NONE;
    }
    const double track_s = now_s() - t0, track_cpu = cpu_s() - c0;

    /* Decode alone; the reader's threads start at open, so the tick readings bracket the open. */
    static task_ticks ta, tb;
    task_ticks_read(&ta);
    src = vis_source_open_video(path, &err);
    if (!src)
        goto out;
    t0 = now_s();
    c0 = cpu_s();
    for (int i = 0; i < frames; i++)
        if (vis_source_read(src, f, NULL, &err) != VIS_OK)
            goto out;
    const double dec_s = now_s() - t0, dec_cpu = cpu_s() - c0;
    task_ticks_read(&tb);
    const int dec_threads = busy_threads(&ta, &tb);
    vis_source_close(src);

    vis_tracker_reset(t);
    src = vis_source_open_video(path, &err);
    if (!src)
        goto out;
    int decoded = 0;
    t0 = now_s();
    c0 = cpu_s();
    for (int i = 0; i < frames; i++) {
        if (vis_source_read(src, f, NULL, &err) != VIS_OK)
            goto out;
        if (vis_tracker_process(t, f, 0.0, &m, &err) != VIS_OK)
            goto out;
        decoded++;
    }
    const double dt_s = now_s() - t0, dt_cpu = cpu_s() - c0;
    printf("{\"bench\":\"vision\",\"width\":%d,\"height\":%d,\"frames\":%d,\"tracked\":%d,"
           "\"track_fps\":%.1f,\"track_cpu_fps\":%.1f,\"decode_fps\":%.1f,\"decode_cpu_fps\":%.1f,"
           "\"decode_threads\":%d,\"decode_track_fps\":%.1f,\"decode_track_cpu_fps\":%.1f,"
           "\"target_track_fps\":500,\"target_decode_track_fps\":150}\n",
           w, h, frames, tracked, frames / track_s, track_cpu > 0 ? frames / track_cpu : 0.0,
           frames / dec_s, dec_cpu > 0 ? frames / dec_cpu : 0.0, dec_threads, decoded / dt_s,
           dt_cpu > 0 ? decoded / dt_cpu : 0.0);
    /* Issue 14: decode + track per format on one core and on every core, and the ROI tracker. */
    char vpath[1100];
    snprintf(vpath, sizeof vpath, "%s/ribbon-vision-bench-%ld-p.mkv", dir && dir[0] ? dir : "/tmp", (long)getpid());
    if (bench_video_format(vpath, "ffv1", mem, frames, w, h, &cal, &tp, &err))
        goto out;
    snprintf(vpath, sizeof vpath, "%s/ribbon-vision-bench-%ld-p.avi", dir && dir[0] ? dir : "/tmp", (long)getpid());
    if (bench_video_format(vpath, "y800", mem, frames, w, h, &cal, &tp, &err))
        goto out;
    if (bench_roi(&rp, &err))
        goto out;
    rc = 0;
out:
    if (rc)
        fprintf(stderr, "ribbonctl vision-bench: %s\n", err.message);
    vis_source_close(src);
    vis_tracker_free(t);
    vis_video_writer_close(vw);
    vis_renderer_free(r);
    for (int i = 0; mem && i < frames; i++)
        vis_frame_free(mem[i]);
    free(mem);
    vis_frame_free(f);
    remove(path);
    return rc;
}
