/* rig_config.h: load a rig file (config/mock.ini, rig-gcode.ini, rig-modbus.ini, replay.ini) into
 * one typed, checked struct rig_config: the mode, the scene it points at (loaded with
 * cfg_scene_load), both rails (rail_config), the trial runner's timings and speeds, the rig
 * calibration, the specimen record, camera, snap detection, prediction resolution, store, API
 * and replay sources.
 *
 * One key table (rig_config_keys()) drives parsing, bounds, the per-mode "required" rule and the
 * README's "Rig files" table, as scene_file.c does for scenes. The rail sections are delegated to
 * rail_config (its own keys), with this loader's line numbers, duplicate check and overrides.
 * Every error names the file, the line (or the --set override, or "default") and "section.key"
 * (cfg_error.h); an error inside the scene file is passed up unchanged. A mode that does not use
 * a part does not require it: keys of unused parts are still checked, then ignored.
 *
 * Paths: inputs (rig.scene, camera.calibration, replay.video, replay.rails) are relative to the
 * rig file's directory; outputs (store.path, camera.video_dir) to the directory rig.outputs
 * names (the rig file's, default, or the working directory at load). Every path in the struct is
 * absolute. Nothing but the scene is opened at load: a mode opens its parts when it runs. */
#ifndef RIBBON_CONFIG_RIG_CONFIG_H
#define RIBBON_CONFIG_RIG_CONFIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cfg_error.h"
#include "rail_config.h"
#include "rig_calib.h"
#include "scene.h"

#define RIG_PATH_MAX 1024  /* bytes of a resolved path, with the terminator */
#define RIG_NAME_MAX 64    /* bytes of a short text value (names, materials, addresses) */
#define RIG_TOKEN_MAX 128  /* bytes of the API token */
#define RIG_LADDER_MAX 8   /* rungs of the prediction ladder */
#define RIG_TOKEN_MIN_LEN 16 /* shortest accepted API token, characters */

/* Longest rig file the loader reads (bytes). */
#define RIG_MAX_FILE_BYTES (1u << 20)

typedef enum rig_mode {
    RIG_MODE_RIG = 0, /* real rails, live camera: lab trials */
    RIG_MODE_MOCK,    /* mock rails, the simulator as the ribbon, synthetic frames */
    RIG_MODE_REPLAY   /* a recorded video and recorded rail positions */
} rig_mode;

typedef enum rig_clock_kind {
    RIG_CLOCK_REAL = 0, /* CLOCK_MONOTONIC */
    RIG_CLOCK_VIRTUAL   /* mock only: rails and simulated ribbon as fast as the computer allows */
} rig_clock_kind;

typedef enum rig_base {
    RIG_BASE_FILE = 0, /* outputs relative to the rig file's directory */
    RIG_BASE_CWD       /* outputs relative to the working directory at load */
} rig_base;

typedef enum rig_crease {
    RIG_CREASE_UNSET = 0, /* not recorded */
    RIG_CREASE_UP,        /* creases turn the tangent toward the surface normal: folds.angle_deg > 0 */
    RIG_CREASE_DOWN       /* away from it: folds.angle_deg < 0 (the paper scenes) */
} rig_crease;

typedef enum rig_source_kind {
    RIG_SOURCE_NONE = 0,   /* no live source (replay mode reads replay.video) */
    RIG_SOURCE_INDEX,      /* V4L2 device index (camera.source = 0, 1, ...) */
    RIG_SOURCE_DEVICE,     /* a device path (camera.source = /dev/video0) */
    RIG_SOURCE_SYNTHETIC,  /* frames rendered from the simulated ribbon (mock) */
    RIG_SOURCE_ARAVIS      /* a GenICam camera through Aravis (camera.source = aravis:ID, device =
                              ID, "" = the first camera) */
} rig_source_kind;

typedef enum rig_roi_kind {
    RIG_ROI_AUTO = 0, /* around the ribbon and clamps, plus camera.margin_px */
    RIG_ROI_FULL,     /* the whole frame */
    RIG_ROI_RECT      /* camera.roi = x,y,w,h (pixels) */
} rig_roi_kind;

typedef struct rig_specimen {
    char name[RIG_NAME_MAX];       /* the specimen's label, e.g. "PET-2024-07 #3" */
    char material[RIG_NAME_MAX];   /* e.g. "PET"; "" = not recorded */
    double crease_angle_left_deg;  /* deg, measured angle of the crease at Gamma; NaN = not measured */
    double crease_angle_right_deg; /* deg, measured angle of the crease at 1 - Gamma; NaN = not measured */
    double crease_position_left;   /* measured position of the left crease (near the clamp at x = 0),
                                      a fraction of the free length in (0, 1); NaN = not measured */
    double crease_position_right;  /* the right crease's, > crease_position_left; NaN = not measured */
    char folded_at[RIG_NAME_MAX];  /* ISO 8601 date-time with a zone, as written; "" = not recorded */
    double folded_at_s;            /* derived: folded_at in s since the Unix epoch; NaN = not recorded */
    rig_crease crease_orientation; /* must match the sign of the scene's folds.angle_deg when set */
    double min_clamp_gap_mm;       /* mm, the clamps never come closer (0 = no specimen limit) */
} rig_specimen;

typedef struct rig_trial {
    double hold_s;              /* s, held at the target compression before checking the upper state */
    double compress_speed_mm_s; /* mm/s, compression rail speed toward the target Delta L */
    double return_speed_mm_s;   /* mm/s, both rails' speed back to where the trial started */
    double min_free_disk_mb;    /* MB (10^6 bytes) free in camera.video_dir before a trial starts */
    double upper_dz_min;        /* Delta Z the camera must see after the hold (upper state) */
    double post_snap_s;         /* s, recorded after the snap before the shear stops and returns */
    /* Derived, not keys: */
    double shear_speed_mm_s;    /* mm/s, the scene's protocol.shear_rate * 1000; the shear rail
                                   jogs at shear_sign * shear_speed_mm_s */
    double compress_target_mm;  /* mm, compression rail position at the scene's Delta L */
    double shear_end_mm;        /* mm, shear rail position at the scene's protocol.shear_max */
} rig_trial;

typedef struct rig_camera {
    rig_source_kind source;     /* what camera.source named */
    int index;                  /* RIG_SOURCE_INDEX: V4L2 device index */
    char device[RIG_PATH_MAX];  /* RIG_SOURCE_DEVICE: the device path */
    double fps;                 /* 1/s, frame rate (camera request, synthetic rate) */
    int width_px, height_px;    /* px, requested frame size; 0 = device / renderer default */
    char calibration[RIG_PATH_MAX]; /* camera calibration file (vis_calib_save), "" = none (mock:
                                       computed from the synthetic camera) */
    rig_roi_kind roi;           /* crop of the saved video */
    int roi_x, roi_y, roi_w, roi_h; /* px, RIG_ROI_RECT only */
    int margin_px;              /* px, margin around ribbon and clamps for RIG_ROI_AUTO */
    char video_dir[RIG_PATH_MAX]; /* where trial videos are written */
    double noise_sigma;         /* grey levels, mock renderer's additive noise */
    double blur_sigma_px;       /* px, mock renderer's optical blur */
    /* GenICam (aravis:) cameras: the sensor ROI origin, exposure and gain asked of the camera. */
    int offset_x_px, offset_y_px; /* px, -1 = the camera's own */
    double exposure_us;         /* us, 0 = the camera's own */
    double gain_db;             /* dB, -1 = the camera's own */
    double v4l2_gain;           /* V4L2 gain control's own units, -1 = the camera's own */
    /* The live pipeline (rig mode, trial_capture.h). */
    int ring_frames;            /* frames the capture ring holds before the video drops */
    int track_max_lag;          /* frames behind the camera after which tracking skips frames */
    int frozen_frames;          /* identical frames in a row that are a frozen image ... */
    double frozen_move_mm;      /* ... mm: while a rail moved at least this much since the first */
    /* Rig mode, after each trial (daemon/trial/trial_transcoder.h): the raw Y800 video
     * transcoded losslessly in the background, verified bit for bit, then the raw file removed. */
    int transcode;              /* RIG_TRANSCODE_OFF or RIG_TRANSCODE_FFV1 */
    /* Rig mode (daemon/trial/trial_cam_watch.h): the camera's time offset measured at each
     * shear's start over time_offset_window_s (0 = not), used for the trial when measure is 1. */
    int time_offset_measure;    /* 0 configured, 1 measure */
    double time_offset_window_s;
    int transcode_keep;         /* RIG_KEEP_RECORDED (every recorded pixel) or RIG_KEEP_TRACKER */
    int transcode_threads;      /* the encoder's slice threads */
} rig_camera;

enum { RIG_TRANSCODE_OFF = 0, RIG_TRANSCODE_FFV1 = 1 };
/* RIG_KEEP_TRACKER: only the tracker's region (ribbon and clamps at the trial's compression plus
 * margin_px, the region roi = auto records) of a video recorded larger (roi = full or x,y,w,h). */
enum { RIG_KEEP_RECORDED = 0, RIG_KEEP_TRACKER = 1 };

typedef struct rig_detect {
    double dz_jump;       /* smallest jump of Delta Z between consecutive frames that is a snap */
    double min_quality;   /* frames tracked below this quality (0..1) are not measured */
    bool torque_witness;  /* use the shear drive's load (torque / following error; mock: the
                             twin's shear force) as a second witness */
    double load_jump;     /* witness: a load jump between consecutive readings above this
                             fraction of the load range seen so far in the shear */
} rig_detect;

typedef struct rig_sim {
    double target_error;             /* relative error on the snap Delta W the prediction must meet */
    int nodes;                       /* explicit N; 0 = chosen from the ladder */
    double dt;                       /* s, explicit time step; 0 = chosen from the ladder */
    bool fast;                       /* adaptive time step (ribbon-sim --fast) */
    int ladder_nodes[RIG_LADDER_MAX]; /* N of each rung, increasing */
    int n_ladder;
    bool explicit_resolution;        /* derived: nodes or dt set, target_error not used */
    bool fit;                        /* the calibrated prediction beside each trial (issue 32 B) */
    char fit_keys[256];              /* comma-separated fit keys; "" = the default set */
    double fit_refresh_s;            /* s of trial time between refreshes in the shear; 0 = none */
    bool fit_shape;                  /* the fit also takes the tracked centreline at ~4 compression
                                        and hold frames (issue 32 A/B, docs/calibration.md) */
    double fit_hinge;                /* N m/rad: the fit's crease hinges when the scene's creases are
                                        rigid (its start and its prior's centre); 0 = the scene's */
    bool specimen_fit;               /* the named specimen refitted from its trials after each one
                                        (its calibration, used by its next prediction; issue 35 A);
                                        off: neither refitted nor used */
} rig_sim;

typedef struct rig_api {
    char listen[RIG_NAME_MAX]; /* IPv4 / IPv6 address or "localhost" */
    int port;                  /* TCP port; 0 = any free port */
    char token[RIG_TOKEN_MAX]; /* bearer token, "" = none (loopback only) */
    bool loopback;             /* derived: listen is a loopback address */
} rig_api;

typedef struct rig_replay {
    char video[RIG_PATH_MAX]; /* recorded video, "" = the source trial's */
    char rails[RIG_PATH_MAX]; /* CSV t_s,compress_mm,shear_mm, "" = the source trial's samples */
    int64_t source_trial;     /* trial id in the store, 0 = none */
} rig_replay;

/* [twin]: the strip in front of the simulated camera, when it is not the scene (mock mode's twin,
 * ribbon-rigsim's). Its keys are scene keys written SECTION.KEY = VALUE (folds.angle_deg = -86,
 * mesh.nodes = 121), also `--set twin.SECTION.KEY=VALUE`; they are applied in order (file lines,
 * then overrides: a later one wins) to a copy of the trial's scene (cfg_scene_apply), so every
 * scene key is a twin key. Mock mode uses it; rig mode checks it and leaves it to ribbon-rigsim
 * (ribbond's rig mode films a real strip); replay mode refuses it (a recorded video has no twin). */
#define RIG_TWIN_KEYS_MAX 32
#define RIG_TWIN_KEY_LEN 200   /* bytes of one "section.key=value", with the terminator */

typedef struct rig_twin {
    bool present;              /* a [twin] section or a twin.* override was given */
    int n;                     /* keys applied */
    char keys[RIG_TWIN_KEYS_MAX][RIG_TWIN_KEY_LEN]; /* "section.key=value" in the order applied */
    rod_scene scene;           /* the trial's scene with the keys applied, checked (present only) */
} rig_twin;

typedef struct rig_config {
    char path[RIG_PATH_MAX];   /* the rig file, absolute */
    char dir[RIG_PATH_MAX];    /* its directory, absolute */
    rig_mode mode;
    rig_clock_kind clock;
    rig_base outputs;
    char scene_path[RIG_PATH_MAX];
    rod_scene scene;           /* loaded and checked, with the scene's --set overrides */
    bool has_rails;            /* both rail sections loaded (always in rig and mock modes) */
    rail_config compress;      /* params.min_gap_mm, gap_at_zero_mm, gap_per_mm come from
                                  [calibration] and [specimen] */
    rail_config shear;
    rig_calibration calib;
    rig_specimen specimen;
    rig_trial trial;
    rig_camera camera;
    rig_detect detect;
    rig_sim sim;
    char store_path[RIG_PATH_MAX];
    rig_api api;
    rig_replay replay;
    rig_twin twin;             /* [twin] (see above); twin.present false: the twin is the scene */
} rig_config;

/* ---- the key table ---------------------------------------------------------------------- */

typedef enum rig_key_type {
    RIG_KEY_DOUBLE, /* one finite decimal number */
    RIG_KEY_INT,    /* one decimal integer */
    RIG_KEY_ID,     /* a positive 64-bit integer */
    RIG_KEY_SIGN,   /* +1 or -1 */
    RIG_KEY_ENUM,   /* one of `names` (stored as an int, the index) */
    RIG_KEY_TEXT,   /* printable text without spaces at the ends */
    RIG_KEY_PATH,   /* a file or directory path, resolved after loading */
    RIG_KEY_LIST,   /* comma-separated increasing integers (sim.ladder_nodes) */
    RIG_KEY_ROI,    /* auto | full | x,y,w,h */
    RIG_KEY_SOURCE  /* camera source: an index, /dev/..., "synthetic" (checked per mode) */
} rig_key_type;

/* Modes as bits, for the `required` and `used` masks. */
enum { RIG_IN_RIG = 1u << RIG_MODE_RIG, RIG_IN_MOCK = 1u << RIG_MODE_MOCK,
       RIG_IN_REPLAY = 1u << RIG_MODE_REPLAY, RIG_IN_ALL = 7u };

enum {
    RIG_KEY_MIN_OPEN = 1u << 0, /* the lower bound itself is refused */
    RIG_KEY_MAX_OPEN = 1u << 1, /* the upper bound itself is refused */
    RIG_KEY_OUTPUT = 1u << 2    /* PATH relative to rig.outputs, not the rig file's directory */
};

typedef struct rig_key {
    const char *section;
    const char *name;
    rig_key_type type;
    size_t offset;            /* offsetof(rig_config, field) */
    size_t size;              /* TEXT / PATH: buffer size */
    double min, max;          /* DOUBLE / INT / LIST elements / TEXT length */
    unsigned flags;
    unsigned required;        /* modes in which the file must set it (RIG_IN_*) */
    const char *const *names; /* ENUM, NULL-terminated */
    const char *unit;         /* "mm", "s", "1", "-" (not a quantity) */
    const char *def;          /* the default as the README shows it */
    const char *doc;          /* one sentence */
} rig_key;

/* The table, in file order. *n gets its length. Static, read-only data. */
const rig_key *rig_config_keys(size_t *n);

/* The sections a rig file may contain, NULL-terminated ("rail.compress", "rail.shear" included). */
const char *const *rig_config_sections(void);

/* ---- loading ---------------------------------------------------------------------------- */

/* Load `path`, apply the overrides "section.key=value" in order (a later one wins), check the
 * result and on success store it in *out. Overrides of a scene key ("protocol.compression=0.4")
 * go to the scene loader; of a rail key ("rail.shear.max_speed_mm_s=20") to that rail. On failure
 * *out is untouched and *err (may be NULL) says why. Returns CFG_OK (0) or the error's status. */
cfg_status rig_config_load(const char *path, const char *const *overrides, int n_overrides,
                           rig_config *out, cfg_error *err);

/* The same on text in memory; `name` is used in errors and `dir` (absolute or relative to the
 * working directory) is where relative paths start. For tests and fuzzing. */
cfg_status rig_config_parse(const char *name, const char *dir, const char *text, size_t len,
                            const char *const *overrides, int n_overrides, rig_config *out,
                            cfg_error *err);

/* ---- uses --------------------------------------------------------------------------------- */

/* The calibration record stored with each trial, as compact JSON: rig_calib_json() of this rig's
 * calibration and the scene's free length (malloc'd, free() it; NULL when out of memory). */
char *rig_calibration_json(const rig_config *c);

/* The specimen record as compact JSON (malloc'd, free() it): name, material, measured crease
 * angles and positions and folded_at (null when not measured), crease_orientation ("up", "down" or null), min_clamp_gap_mm,
 * and the scene's geometry and material (length_m, width_m, thickness_m, youngs_modulus_pa,
 * density_kg_m3, fold_angle_deg, fold_position). */
char *rig_specimen_json(const rig_config *c);

/* Rail positions (mm) <-> Delta L, Delta W with this rig's calibration and the scene's free
 * length (rig_calib.h). Either output pointer may be NULL. */
void rig_config_rails_to_norm(const rig_config *c, double compress_mm, double shear_mm,
                              double *dl, double *dw);
void rig_config_norm_to_rails(const rig_config *c, double dl, double dw, double *compress_mm,
                              double *shear_mm);

const char *rig_mode_name(rig_mode m); /* "rig", "mock", "replay" */

#endif
