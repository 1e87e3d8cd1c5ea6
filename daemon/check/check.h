/* check.h: the face of daemon/check/, the rig's readiness checks (issue 34 E): one list of lines,
 * each ok / warn / fail with what was found and what to do, over every part a rig file names.
 * `ribbonctl check` prints it; ribbond runs it at start and on request and refuses trials while a
 * fail stands.
 *
 *   part            checks (file)
 *   rail NAME       port exists and is writable by the service user (check_access.c,
 *                   check_rails.c); the device lock (a rail a running ribbond holds is reported,
 *                   not opened); the GRBL settings check of the G-code driver, the Modbus map
 *                   probe; opened without moving: homing state, alarms, a controller that reset;
 *                   soft limits against the travel, the trial's targets and the specimen's
 *                   minimum clamp gap
 *   camera          found, pixel format, frame size against the calibration, exposure
 *                   settable and auto-exposure off (check_camera.c)
 *   store, disk     the store file and its directory writable by the service user, a write
 *                   probe, free disk for CHECK_TRIALS trials of raw video (check_disk.c); replay
 *                   mode: the store, and trial.min_free_disk_mb free where it is
 *
 * Nothing here moves a rail: rails are opened (which cancels any motion a controller still
 * runs), read and closed. The camera is opened only to read its format (V4L2: ioctls, no
 * stream) or one frame (GenICam). Every outside dependency a test needs to fault is in
 * check_env: the service user, rails already open (ribbond's own), statvfs, the camera probe. */
#ifndef RIBBON_DAEMON_CHECK_H
#define RIBBON_DAEMON_CHECK_H

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <sys/statvfs.h>

#include "rail.h"
#include "rig_config.h"

#define CHECK_MAX_ITEMS 48
#define CHECK_TRIALS 50 /* trials of raw video the free disk should hold */

typedef enum check_level {
    CHECK_OK = 0, /* ready */
    CHECK_WARN,   /* works, but look at it */
    CHECK_FAIL    /* the rig must not run trials until this is fixed */
} check_level;

typedef struct check_item {
    check_level level;
    char part[32];  /* "rail compress", "camera", "store", "disk" */
    char what[32];  /* "port", "settings", "state", "limits", "map", "format", ... */
    char text[480]; /* what was found and, unless ok, what to do */
} check_item;

typedef struct check_report {
    int n;             /* items (a report that overflowed ends with a fail saying so) */
    int fails, warns;
    check_item items[CHECK_MAX_ITEMS];
} check_report;

/* ---- the report (check_report.c) ------------------------------------------------------------ */

void check_report_init(check_report *r);
void check_add(check_report *r, check_level l, const char *part, const char *what, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
const char *check_level_name(check_level l); /* "ok", "warn", "fail" */
/* One line per item: "fail  rail shear   port      TEXT", then a summary line. */
void check_report_print(const check_report *r, FILE *f);
/* {"ok": bool, "fails": N, "warns": N, "checks": [{"level","part","what","text"}, ...]} */
json_t *check_report_json(const check_report *r);

/* ---- who must be able to write (check_access.c) -------------------------------------------- */

/* 0 when `user` (NULL: the calling user, by access(2)) may write path; else -1 and why names the
 * mode, owner and group (for a user name that does not exist as well). Mode bits only: ACLs and
 * read-only mounts are found by the write probe (check_disk.c) instead. */
int check_writable_by(const char *path, const char *user, char *why, size_t why_len);

/* ---- the environment a run sees -------------------------------------------------------------- */

typedef struct check_camera_facts {
    bool found;            /* the camera answered */
    char why[300];         /* !found: the reason */
    char fourcc[8];        /* pixel format ("YUYV", "GREY", "Mono8"), "" = not known */
    int width_px, height_px; /* the frames it gives */
    int exposure;          /* 1 settable and held (auto off or offable), 0 not settable, -1 unknown */
    char exposure_text[160]; /* what was found about exposure */
} check_camera_facts;

typedef struct check_env {
    const char *service_user; /* whose access counts ("ribbon"); NULL: the calling user */
    rail *compress, *shear;   /* rails already open and locked by the caller (ribbond); NULL:
                                 the run takes the locks and opens them itself */
    const char *rails_why;    /* the caller could not open its rails: this is why (a fail) */
    int (*statvfs_fn)(const char *path, struct statvfs *out); /* statvfs(3) */
    /* The camera probe (check_camera_probe); 0, or -1 when it could not be asked at all. */
    int (*camera_probe)(const rig_config *cfg, check_camera_facts *out);
    int trials;               /* trials of video the disk should hold (CHECK_TRIALS) */
} check_env;

check_env check_env_default(void);

/* ---- the parts ------------------------------------------------------------------------------- */

void check_rails(const rig_config *cfg, const check_env *env, check_report *r);       /* check_rails.c */
void check_rail_limits(const rig_config *cfg, check_report *r);                       /* check_rails.c */
int check_camera_probe(const rig_config *cfg, check_camera_facts *out);               /* check_camera.c */
void check_camera(const rig_config *cfg, const check_env *env, check_report *r);      /* check_camera.c */
void check_store(const rig_config *cfg, const check_env *env, check_report *r);       /* check_disk.c */
void check_disk(const rig_config *cfg, const check_env *env, check_report *r);        /* check_disk.c */
/* Replay mode: trial.min_free_disk_mb free where the store is (a replay writes nothing else). */
void check_store_disk(const rig_config *cfg, const check_env *env, check_report *r);  /* check_disk.c */
/* Bytes of raw Y800 video one trial of this rig file records (full frames at camera.fps over
 * the protocol's duration); the duration in s into *seconds (may be NULL). */
double check_trial_video_bytes(const rig_config *cfg, int width_px, int height_px, double *seconds);

/* Every check of the parts the rig file's mode uses, appended to r (check_report_init it first;
 * check_rig.c). */
void check_rig_run(const rig_config *cfg, const check_env *env, check_report *r);

#endif
