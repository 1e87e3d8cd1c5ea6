/* check_disk.c: can the rig keep what its trials record? The store: its file (if it exists yet)
 * and its directory (SQLite's -wal and -shm files go beside it) writable by the service user, and
 * a write probe there (a small file written, synced and removed: it finds a read-only mount or a
 * full disk, which the mode bits do not show). The videos: free disk in camera.video_dir for
 * check_env.trials trials of raw Y800 video (a trial records every frame raw; camera.transcode
 * shrinks it afterwards, so the raw size is what a trial needs while it runs). Below one trial's
 * video (or trial.min_free_disk_mb, if larger) is a fail: the trial would be refused; below
 * `trials` trials is a warning. A replay records no video: all it writes is its trial's rows in
 * the store, so its disk check is trial.min_free_disk_mb free in the store's directory. */
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"

/* Protocol duration (s) and bytes of full-frame Y800 video at camera.fps over it: compression
 * from Delta L = 0 to the target, the hold, the shear to protocol.shear_max (the longest a trial
 * shears) and the time recorded after a snap (the return is not filmed). An upper bound: a trial
 * that snaps stops shearing post_snap_s after the snap (`make rehearsal`: 85 s filmed, 117 s here). */
double check_trial_video_bytes(const rig_config *cfg, int width_px, int height_px, double *seconds)
{
    const rig_trial *t = &cfg->trial;
    double dc = fabs(t->compress_target_mm - cfg->calib.compress_zero_mm);
    double ds = fabs(t->shear_end_mm - cfg->calib.shear_zero_mm);
    double s = 0.0;
    if (t->compress_speed_mm_s > 0) s += dc / t->compress_speed_mm_s;
    s += t->hold_s;
    if (t->shear_speed_mm_s > 0) s += ds / t->shear_speed_mm_s;
    s += t->post_snap_s; /* recording ends there: the return is not filmed */
    if (seconds) *seconds = s;
    double fps = cfg->camera.fps > 0 ? cfg->camera.fps : 30.0;
    return (double)width_px * (double)height_px * fps * s;
}

/* The nearest existing directory at or above path (for a directory a trial creates). */
static void existing_dir(const char *path, char *out, size_t n)
{
    snprintf(out, n, "%s", path);
    struct stat sb;
    for (int i = 0; i < 64 && stat(out, &sb) != 0; i++) {
        char *slash = strrchr(out, '/');
        if (!slash || slash == out) {
            snprintf(out, n, "/");
            return;
        }
        *slash = 0;
    }
}

/* Writes, syncs and removes a small file in dir: 0, or -1 with why (read-only, full, ...). */
static int write_probe(const char *dir, char *why, size_t why_len)
{
    char p[RIG_PATH_MAX + 64];
    snprintf(p, sizeof p, "%s/.ribbon-check-%ld", dir, (long)getpid());
    int fd = open(p, O_WRONLY | O_CREAT | O_EXCL, 0600);
    if (fd < 0) {
        snprintf(why, why_len, "cannot create a file in %.300s: %s", dir, strerror(errno));
        return -1;
    }
    static const char block[4096];
    int rc = 0;
    for (int i = 0; i < 16 && !rc; i++)
        if (write(fd, block, sizeof block) != (ssize_t)sizeof block) rc = -1;
    if (!rc && fsync(fd) != 0) rc = -1;
    if (rc) snprintf(why, why_len, "writing 64 KiB in %.300s failed: %s", dir, strerror(errno));
    close(fd);
    unlink(p);
    return rc;
}

void check_store(const rig_config *cfg, const check_env *env, check_report *r)
{
    char tmp[RIG_PATH_MAX], dir[RIG_PATH_MAX], why[600];
    snprintf(tmp, sizeof tmp, "%s", cfg->store_path);
    snprintf(dir, sizeof dir, "%s", dirname(tmp));
    const char *who = env->service_user ? env->service_user : "this user";
    struct stat sb;
    if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) {
        check_add(r, CHECK_FAIL, "store", "writable", "the store's directory %.300s does not exist: make it, owned by "
                  "%s", dir, who);
        return;
    }
    if (check_writable_by(dir, env->service_user, why, sizeof why)) {
        check_add(r, CHECK_FAIL, "store", "writable", "%s: the store's directory must be (its -wal and -shm files "
                  "go there); chown it to %s or set store.path", why, who);
        return;
    }
    int exists = stat(cfg->store_path, &sb) == 0;
    if (exists && check_writable_by(cfg->store_path, env->service_user, why, sizeof why)) {
        check_add(r, CHECK_FAIL, "store", "writable", "%s: chown it to %s", why, who);
        return;
    }
    if (write_probe(dir, why, sizeof why)) {
        check_add(r, CHECK_FAIL, "store", "writable", "%s: free the disk, or set store.path on a writable one", why);
        return;
    }
    check_add(r, CHECK_OK, "store", "writable", "%.300s %s, writable by %s", cfg->store_path,
              exists ? "exists" : "will be made", who);
}

static void human_bytes(double b, char *out, size_t n)
{
    if (b >= 1e9) snprintf(out, n, "%.1f GB", b / 1e9);
    else snprintf(out, n, "%.0f MB", b / 1e6);
}

void check_disk(const rig_config *cfg, const check_env *env, check_report *r)
{
    char dir[RIG_PATH_MAX];
    existing_dir(cfg->camera.video_dir, dir, sizeof dir);
    struct statvfs fs;
    int (*sv)(const char *, struct statvfs *) = env->statvfs_fn ? env->statvfs_fn : statvfs;
    if (sv(dir, &fs) != 0) {
        check_add(r, CHECK_FAIL, "disk", "free", "statvfs %.300s: %s", dir, strerror(errno));
        return;
    }
    char why[600];
    if (check_writable_by(dir, env->service_user, why, sizeof why)) {
        check_add(r, CHECK_FAIL, "disk", "videos", "%s: camera.video_dir %.300s must be writable by %s", why,
                  cfg->camera.video_dir, env->service_user ? env->service_user : "this user");
    }
    int w = cfg->camera.width_px > 0 ? cfg->camera.width_px : 640;
    int h = cfg->camera.height_px > 0 ? cfg->camera.height_px : 480;
    double secs = 0.0;
    double per = check_trial_video_bytes(cfg, w, h, &secs);
    double free_b = (double)fs.f_bavail * (double)fs.f_frsize;
    double one = per > cfg->trial.min_free_disk_mb * 1e6 ? per : cfg->trial.min_free_disk_mb * 1e6;
    int trials = env->trials > 0 ? env->trials : CHECK_TRIALS;
    char fb[32], pb[32], nb[32];
    human_bytes(free_b, fb, sizeof fb);
    human_bytes(per, pb, sizeof pb);
    human_bytes(per * trials, nb, sizeof nb);
    double fit = per > 0 ? floor(free_b / per) : INFINITY;
    if (free_b < one) {
        char ob[32];
        human_bytes(one, ob, sizeof ob);
        check_add(r, CHECK_FAIL, "disk", "free", "%s free in %.300s, a trial needs %s (%s of raw video: %d x %d at "
                  "%.0f fps for %.0f s; trial.min_free_disk_mb %.0f): free the disk or move camera.video_dir",
                  fb, dir, ob, pb, w, h, cfg->camera.fps, secs, cfg->trial.min_free_disk_mb);
    } else if (free_b < per * trials) {
        check_add(r, CHECK_WARN, "disk", "free", "%s free in %.300s: room for %.0f trials, not %d (%s each: %d x %d at "
                  "%.0f fps for %.0f s raw; %d need %s): free the disk before a campaign", fb, dir, fit, trials, pb, w,
                  h, cfg->camera.fps, secs, trials, nb);
    } else {
        check_add(r, CHECK_OK, "disk", "free", "%s free in %.300s: %d trials of raw video need %s (%s each: %d x %d "
                  "at %.0f fps for %.0f s)", fb, dir, trials, nb, pb, w, h, cfg->camera.fps, secs);
    }
}

void check_store_disk(const rig_config *cfg, const check_env *env, check_report *r)
{
    char tmp[RIG_PATH_MAX], dir[RIG_PATH_MAX];
    snprintf(tmp, sizeof tmp, "%s", cfg->store_path);
    existing_dir(dirname(tmp), dir, sizeof dir);
    struct statvfs fs;
    int (*sv)(const char *, struct statvfs *) = env->statvfs_fn ? env->statvfs_fn : statvfs;
    if (sv(dir, &fs) != 0) {
        check_add(r, CHECK_FAIL, "disk", "free", "statvfs %.300s: %s", dir, strerror(errno));
        return;
    }
    double free_b = (double)fs.f_bavail * (double)fs.f_frsize, need = cfg->trial.min_free_disk_mb * 1e6;
    char fb[32], nb[32];
    human_bytes(free_b, fb, sizeof fb);
    human_bytes(need, nb, sizeof nb);
    if (free_b < need)
        check_add(r, CHECK_FAIL, "disk", "free", "%s free in %.300s (the store's directory: all a replay writes), a "
                  "replay needs %s (trial.min_free_disk_mb): free the disk or set store.path on another", fb, dir, nb);
    else
        check_add(r, CHECK_OK, "disk", "free", "%s free in %.300s (the store's directory: all a replay writes), at "
                  "least %s (trial.min_free_disk_mb)", fb, dir, nb);
}
