/* ctl_transcode.c: `ribbonctl transcode`: a raw trial video to lossless FFV1 by hand (what ribbond
 * does after each rig trial, trial_transcode.h), and its benchmark, one JSON line.
 *
 *   ribbonctl transcode RAW.avi [--out OUT.mkv] [--threads N] [--slices N] [--coder C] [--crop X,Y,W,H] [--keep-raw]
 *   ribbonctl transcode --bench VIDEO [--frames N] [--threads N] [--slices N] [--trial-s S] [--dir DIR]
 *
 * The benchmark writes the first N frames of VIDEO (any video OpenCV reads, e.g. `ribbonctl
 * render`'s twin at 640 x 480 and 60 fps) as raw Y800 AVI, the rig recorder's format, in DIR
 * (default TMPDIR or /tmp; removed afterwards), then times on that file: the libavcodec FFV1
 * transcode with one encoder thread and with N (each with its bit-for-bit verify, timed apart),
 * and OpenCV's FFV1 writer on the same frames held in memory. The per-trial figures scale the
 * measured bytes and seconds per frame to a trial of S seconds (default 85, the rehearsal's) at
 * the video's frame rate. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "ctl.h"
#include "trial.h"
#include "vision.h"

#define TC_MAX_FRAMES 20000

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ribbonctl transcode RAW.avi [--out OUT.mkv] [--threads N] [--slices N] [--coder C] [--crop X,Y,W,H] [--keep-raw]\n"
            "       ribbonctl transcode --bench VIDEO [--frames N] [--threads N] [--slices N] [--coder C] [--trial-s S] [--dir DIR]\n"
            "  Transcodes a raw Y800 video (a rig trial's trial-N.avi) to lossless FFV1 in Matroska through\n"
            "  libavcodec, decodes both files again and compares every pixel, and only then removes the raw\n"
            "  file (ribbond does this after each rig trial: camera.transcode). The frame-time file\n"
            "  RAW.frames.csv is left in place (replay finds it for OUT.mkv too).\n"
            "options:\n"
            "  --out OUT.mkv     output (default: RAW with .mkv for .avi)\n"
            "  --threads N       encoder slice threads, 1..16 (2)\n"
            "  --slices N        FFV1 slices per frame: 4, 6, 9, 12, 16, 24 or 30 (4)\n"
            "  --coder C         FFV1 entropy coder: rice (faster) or range (smaller) (rice)\n"
            "  --crop X,Y,W,H    keep only this region of the raw frames, pixels\n"
            "  --keep-raw        keep the raw file after a good verify\n"
            "  --bench VIDEO     benchmark on VIDEO's frames written as raw Y800 (nothing of VIDEO changed)\n"
            "  --frames N        frames of VIDEO the benchmark uses (all, at most %d)\n"
            "  --trial-s S       trial length the per-trial figures scale to, seconds (85)\n"
            "  --dir DIR         where the benchmark writes its files (TMPDIR or /tmp)\n"
            "stdout: transcode: one line with frames, bytes and seconds; --bench: one JSON line\n"
            "  {\"bench\":\"transcode\", width, height, fps, frames, raw_bytes, ffv1_bytes, ratio, threads,\n"
            "  coder, encode_s_1thread, encode_s, verify_s, cpu_s_1thread, cpu_s (encode + verify, every\n"
            "  thread), opencv_ffv1_s, opencv_ffv1_cpu_s, opencv_ffv1_bytes, trial_s, raw_bytes_per_trial,\n"
            "  ffv1_bytes_per_trial, transcode_s_per_trial, transcode_cpu_s_per_trial, load1}.\n"
            "  Exit status: 0 done (verified), 1 failed (the raw file kept), 2 usage.\n",
            TC_MAX_FRAMES);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int int_arg(const char *opt, const char *v, int lo, int hi, int *out)
{
    char *end;
    long x = v ? strtol(v, &end, 10) : 0;
    if (!v || *end || x < lo || x > hi) {
        fprintf(stderr, "ribbonctl transcode: %s needs an integer in [%d, %d]\n", opt, lo, hi);
        return -1;
    }
    *out = (int)x;
    return 0;
}

/* CPU seconds of the whole process (every thread: the encoder's slice threads too). */
static double cpu_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static long long file_bytes(const char *p)
{
    struct stat sb;
    return stat(p, &sb) == 0 ? (long long)sb.st_size : -1;
}

/* The benchmark (see the top of the file). */
static int bench(const char *video, int max_frames, const trial_transcode_params *tp, double trial_s, const char *dir)
{
    vis_error ve = {0};
    vis_source *src = vis_source_open_video(video, &ve);
    if (!src) {
        fprintf(stderr, "ribbonctl transcode: %s\n", ve.message);
        return 1;
    }
    double fps = vis_source_fps(src);
    if (!(fps > 0)) fps = 60.0;
    vis_frame **frames = calloc(TC_MAX_FRAMES, sizeof *frames);
    int n = 0, rc = 1;
    char raw[1024], out[1024], cv[1024];
    snprintf(raw, sizeof raw, "%s/ribbon-transcode-bench-%ld.avi", dir, (long)getpid());
    snprintf(out, sizeof out, "%s/ribbon-transcode-bench-%ld.mkv", dir, (long)getpid());
    snprintf(cv, sizeof cv, "%s/ribbon-transcode-bench-%ld-opencv.mkv", dir, (long)getpid());
    vis_video_writer *vw = NULL;
    while (frames && n < max_frames) {
        vis_frame *f = vis_frame_alloc(16, 16, 1, &ve);
        if (!f) break;
        if (vis_source_read(src, f, NULL, &ve) != VIS_OK) {
            vis_frame_free(f);
            break;
        }
        if (!vw) vw = vis_video_writer_open_y800(raw, vis_frame_width(f) & ~1, vis_frame_height(f) & ~1, fps, &ve);
        if (!vw || vis_frame_width(f) % 2 || vis_frame_height(f) % 2) {
            fprintf(stderr, "ribbonctl transcode: raw video %s: %s\n", raw, vw ? "odd frame size" : ve.message);
            vis_frame_free(f);
            goto done;
        }
        if (vis_video_writer_write(vw, f, &ve) != VIS_OK) {
            fprintf(stderr, "ribbonctl transcode: %s\n", ve.message);
            vis_frame_free(f);
            goto done;
        }
        frames[n++] = f;
    }
    vis_video_writer_close(vw);
    vw = NULL;
    if (n == 0) {
        fprintf(stderr, "ribbonctl transcode: no frame read from %s\n", video);
        goto done;
    }
    int w = vis_frame_width(frames[0]), h = vis_frame_height(frames[0]);
    trial_transcode_params p1 = *tp;
    p1.keep_raw = 1;
    p1.threads = 1;
    trial_transcode_result r1, rn;
    char why[640];
    double c0 = cpu_s();
    if (trial_transcode_run(raw, out, &p1, &r1, why, sizeof why)) {
        fprintf(stderr, "ribbonctl transcode: %s\n", why);
        goto done;
    }
    double cpu1 = cpu_s() - c0;
    unlink(out);
    trial_transcode_params pn = *tp;
    pn.keep_raw = 1;
    if (trial_transcode_run(raw, out, &pn, &rn, why, sizeof why)) {
        fprintf(stderr, "ribbonctl transcode: %s\n", why);
        goto done;
    }
    double cpun = cpu_s() - c0 - cpu1;
    /* OpenCV's FFV1 writer on the same frames, from memory (the writer alone is timed). */
    vis_video_writer *ow = vis_video_writer_open(cv, w, h, 1, fps, &ve);
    if (!ow) {
        fprintf(stderr, "ribbonctl transcode: %s\n", ve.message);
        goto done;
    }
    double t0 = now_s(), c1 = cpu_s();
    for (int k = 0; k < n; k++)
        if (vis_video_writer_write(ow, frames[k], &ve) != VIS_OK) break;
    vis_video_writer_close(ow);
    double cv_s = now_s() - t0, cv_cpu = cpu_s() - c1;
    double load1 = -1;
    FILE *la = fopen("/proc/loadavg", "r");
    if (la) {
        if (fscanf(la, "%lf", &load1) != 1) load1 = -1;
        fclose(la);
    }
    double per_trial = trial_s * fps / n;
    printf("{\"bench\":\"transcode\",\"video\":\"%s\",\"width\":%d,\"height\":%d,\"fps\":%.6g,\"frames\":%d,"
           "\"raw_bytes\":%lld,\"ffv1_bytes\":%lld,\"ratio\":%.4f,\"threads\":%d,\"slices\":%d,\"coder\":\"%s\","
           "\"encode_s_1thread\":%.3f,\"encode_s\":%.3f,\"verify_s\":%.3f,\"cpu_s_1thread\":%.3f,\"cpu_s\":%.3f,"
           "\"opencv_ffv1_s\":%.3f,\"opencv_ffv1_cpu_s\":%.3f,"
           "\"opencv_ffv1_bytes\":%lld,\"trial_s\":%.6g,\"raw_bytes_per_trial\":%.0f,\"ffv1_bytes_per_trial\":%.0f,"
           "\"transcode_s_per_trial\":%.1f,\"transcode_cpu_s_per_trial\":%.1f,\"load1\":%.2f}\n",
           video, w, h, fps, n, (long long)rn.raw_bytes, (long long)rn.out_bytes,
           (double)rn.out_bytes / (double)rn.raw_bytes, pn.threads, pn.slices, pn.range_coder ? "range" : "rice", r1.encode_s, rn.encode_s, rn.verify_s, cpu1, cpun,
           cv_s, cv_cpu, file_bytes(cv), trial_s, (double)rn.raw_bytes * per_trial, (double)rn.out_bytes * per_trial,
           (rn.encode_s + rn.verify_s) * per_trial, cpun * per_trial, load1);
    rc = 0;
done:
    vis_video_writer_close(vw);
    for (int k = 0; k < n; k++) vis_frame_free(frames[k]);
    free(frames);
    vis_source_close(src);
    unlink(raw);
    unlink(out);
    unlink(cv);
    return rc;
}

int ctl_transcode_main(int argc, char **argv)
{
    const char *raw = NULL, *out = NULL, *video = NULL, *dir = NULL;
    trial_transcode_params tp = trial_transcode_params_default();
    int frames = TC_MAX_FRAMES;
    double trial_s = 85.0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--out") && v) {
            out = v, i++;
        } else if (!strcmp(a, "--bench") && v) {
            video = v, i++;
        } else if (!strcmp(a, "--dir") && v) {
            dir = v, i++;
        } else if (!strcmp(a, "--threads")) {
            if (int_arg(a, v, 1, 16, &tp.threads)) return 2;
            i++;
        } else if (!strcmp(a, "--slices")) {
            if (int_arg(a, v, 4, 30, &tp.slices)) return 2;
            i++;
        } else if (!strcmp(a, "--frames")) {
            if (int_arg(a, v, 1, TC_MAX_FRAMES, &frames)) return 2;
            i++;
        } else if (!strcmp(a, "--trial-s") && v) {
            char *end;
            trial_s = strtod(v, &end);
            if (*end || !(trial_s > 0 && trial_s < 1e6)) {
                fprintf(stderr, "ribbonctl transcode: --trial-s needs seconds in (0, 1e6)\n");
                return 2;
            }
            i++;
        } else if (!strcmp(a, "--crop") && v) {
            char tail;
            if (sscanf(v, "%d,%d,%d,%d%c", &tp.crop_x, &tp.crop_y, &tp.crop_w, &tp.crop_h, &tail) != 4 ||
                tp.crop_x < 0 || tp.crop_y < 0 || tp.crop_w < 16 || tp.crop_h < 16) {
                fprintf(stderr, "ribbonctl transcode: --crop needs X,Y,W,H (pixels, W and H at least 16)\n");
                return 2;
            }
            i++;
        } else if (!strcmp(a, "--coder") && v) {
            if (strcmp(v, "range") && strcmp(v, "rice")) {
                fprintf(stderr, "ribbonctl transcode: --coder is range or rice\n");
                return 2;
            }
            tp.range_coder = !strcmp(v, "range");
            i++;
        } else if (!strcmp(a, "--keep-raw")) {
            tp.keep_raw = 1;
        } else if (a[0] != '-' && !raw) {
            raw = a;
        } else {
            fprintf(stderr, "ribbonctl transcode: unknown or incomplete option %s\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (video) {
        if (!dir) dir = getenv("TMPDIR") && *getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
        return bench(video, frames, &tp, trial_s, dir);
    }
    if (!raw) {
        usage(stderr);
        return 2;
    }
    char def[1024];
    if (!out) {
        size_t l = strlen(raw);
        if (l < 5 || strcmp(raw + l - 4, ".avi") != 0 || l + 1 > sizeof def) {
            fprintf(stderr, "ribbonctl transcode: %s is not an .avi: give --out OUT.mkv\n", raw);
            return 2;
        }
        snprintf(def, sizeof def, "%.*s.mkv", (int)(l - 4), raw);
        out = def;
    }
    trial_transcode_result r;
    char why[640];
    if (trial_transcode_run(raw, out, &tp, &r, why, sizeof why)) {
        fprintf(stderr, "ribbonctl %s%s (the raw file is kept)\n", strncmp(why, "transcode", 9) ? "transcode: " : "", why);
        return 1;
    }
    printf("%s: %ld frames %dx%d verified bit for bit; %lld -> %lld bytes (%.3f); encode %.2f s, verify %.2f s; %s\n",
           out, r.frames, r.width, r.height, (long long)r.raw_bytes, (long long)r.out_bytes,
           r.raw_bytes > 0 ? (double)r.out_bytes / (double)r.raw_bytes : 0.0, r.encode_s, r.verify_s,
           r.raw_removed ? "raw removed" : "raw kept");
    return 0;
}
