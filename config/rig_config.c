/* rig_config.c: the rig file loader. Owns the rig key table, the per-mode rules, path resolution
 * and the checks that involve the scene, the rails and the calibration together.
 *
 * Design (as scene_file.c, after Redis's config.c): one static table lists every key of the rig's
 * own sections with its type, bounds, offset into rig_config, unit, default, the modes that
 * require it and a doc line; parsing, range checks, the "missing key" rule and the README table
 * follow from it. The rail sections are rail_config's: each line is validated at once on a scratch
 * rail_config (so a bad value is named at its line) and kept, then applied in a fixed order (the
 * Modbus preset `map` first, then the rest in file order, then overrides), so the result does not
 * depend on where `map` sits.
 *
 * Load order, first error wins: the file (syntax, unknown, duplicate, bad value) -> overrides ->
 * keys the mode requires (only the file counts: an override cannot stand in for a required key,
 * a rig file is the record of a trial) -> paths -> the scene (its errors pass up unchanged) ->
 * rails -> mode rules -> cross-checks. A check names the key most to blame at the line or --set
 * that last set it, or "default". Nothing reaches the caller's struct unless all of it passes. */
#include "rig_config.h"

#include <arpa/inet.h>
#include <ctype.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cfg_datetime.h"
#include "cfg_ini.h"
#include "cfg_keys.h"
#include "cfg_number.h"
#include "scene_file.h"

_Static_assert(sizeof(rig_mode) == sizeof(int), "enums are stored as ints");
_Static_assert(sizeof(rig_crease) == sizeof(int), "enums are stored as ints");
_Static_assert(sizeof(rig_camera_side) == sizeof(int), "enums are stored as ints");

#define OFF(field) offsetof(rig_config, field)
#define SZ(field) sizeof(((rig_config *)0)->field)
#define MINO RIG_KEY_MIN_OPEN
#define MAXO RIG_KEY_MAX_OPEN
#define OUT RIG_KEY_OUTPUT
#define ALL RIG_IN_ALL
#define RIG RIG_IN_RIG
#define REPLAY RIG_IN_REPLAY

/* Flag of ENUM keys whose C enum reserves 0 for "not set": the first name is stored as 1. */
#define ENUM1 (1u << 8)
/* Flag of DOUBLE keys that hold a boolean (on | off) instead: names = on_off. */
#define SWITCH (1u << 9)

static const char *const mode_names[] = {"rig", "mock", "replay", NULL};
static const char *const clock_names[] = {"real", "virtual", NULL};
static const char *const base_names[] = {"file", "cwd", NULL};
static const char *const side_names[] = {"front", "back", NULL};
static const char *const crease_names[] = {"up", "down", NULL};
static const char *const off_on[] = {"off", "on", NULL};
static const char *const transcode_names[] = {"off", "ffv1", NULL};
static const char *const keep_names[] = {"recorded", "tracker", NULL};
static const char *const time_offset_names[] = {"configured", "measure", NULL};

/* The key table. Bounds catch typos and keep later arithmetic finite; what depends on several
 * keys (limits against the scene, speeds against the rails) is checked after loading. */
static const rig_key rig_keys[] = {
    {"rig", "mode", RIG_KEY_ENUM, OFF(mode), 0, 0, 0, 0, ALL, mode_names, "-", "required",
     "rig: real rails and camera; mock: mock rails, the simulator as the ribbon, synthetic frames; "
     "replay: a recorded video and rail positions"},
    {"rig", "scene", RIG_KEY_PATH, OFF(scene_path), SZ(scene_path), 0, 0, 0, ALL, NULL, "-",
     "required",
     "scene file (specimen geometry, folds, protocol, solver), relative to the rig file's directory"},
    {"rig", "clock", RIG_KEY_ENUM, OFF(clock), 0, 0, 0, 0, 0, clock_names, "-",
     "virtual in mock mode, real otherwise",
     "virtual (mock mode only): rails and simulated ribbon run as fast as the computer allows"},
    {"rig", "outputs", RIG_KEY_ENUM, OFF(outputs), 0, 0, 0, 0, 0, base_names, "-", "file",
     "where relative output paths (store.path, camera.video_dir) start: file = the rig file's "
     "directory, cwd = the working directory"},

    {"trial", "hold_s", RIG_KEY_DOUBLE, OFF(trial.hold_s), 0, 0.0, 3600.0, 0, 0, NULL, "s", "2",
     "time held at the target compression before checking the upper state"},
    {"trial", "compress_speed_mm_s", RIG_KEY_DOUBLE, OFF(trial.compress_speed_mm_s), 0, 0.0,
     1000.0, MINO, 0, NULL, "mm/s", "2",
     "compression rail speed to the target Delta L (at most rail.compress.max_speed_mm_s)"},
    {"trial", "return_speed_mm_s", RIG_KEY_DOUBLE, OFF(trial.return_speed_mm_s), 0, 0.0, 1000.0,
     MINO, 0, NULL, "mm/s", "5",
     "speed of both rails back to where the trial started (at most either max_speed_mm_s)"},
    {"trial", "min_free_disk_mb", RIG_KEY_DOUBLE, OFF(trial.min_free_disk_mb), 0, 0.0, 1e9, 0, 0,
     NULL, "MB", "1000", "free space needed in camera.video_dir before a trial starts (10^6 bytes); replay mode: in the store's directory"},
    {"trial", "upper_dz_min", RIG_KEY_DOUBLE, OFF(trial.upper_dz_min), 0, 0.0, 1.0, MINO | MAXO,
     0, NULL, "1", "0.05",
     "Delta Z the camera must see after the hold (the upper state), else the trial aborts"},
    {"trial", "post_snap_s", RIG_KEY_DOUBLE, OFF(trial.post_snap_s), 0, 0.0, 600.0, 0, 0, NULL,
     "s", "2", "time recorded after the snap before the shear stops and the rails return"},

    {"calibration", "compress_zero_mm", RIG_KEY_DOUBLE, OFF(calib.compress_zero_mm), 0, -1e6,
     1e6, 0, ALL, NULL, "mm", "required",
     "compression rail position where the clamp gap equals the free length (Delta L = 0); "
     "measured, not driven to"},
    {"calibration", "shear_zero_mm", RIG_KEY_DOUBLE, OFF(calib.shear_zero_mm), 0, -1e6, 1e6, 0,
     ALL, NULL, "mm", "required", "shear rail position where the clamps are aligned (Delta W = 0)"},
    {"calibration", "compress_sign", RIG_KEY_SIGN, OFF(calib.compress_sign), 0, 0, 0, 0, ALL,
     NULL, "1", "required",
     "+1 if a larger compression rail position closes the clamps (Delta L grows), else -1"},
    {"calibration", "shear_sign", RIG_KEY_SIGN, OFF(calib.shear_sign), 0, 0, 0, 0, ALL, NULL, "1",
     "required",
     "+1 if a larger shear rail position moves the shear clamp toward the simulator's +y, else -1"},
    {"calibration", "camera_side", RIG_KEY_ENUM, OFF(calib.camera_side), 0, 0, 0, 0, 0,
     side_names, "-", "front",
     "side the camera looks from: front (-y, looking along +y) or back (flips the sign of A)"},
    {"calibration", "camera_time_offset_s", RIG_KEY_DOUBLE, OFF(calib.camera_time_offset_s), 0,
     -60.0, 60.0, 0, 0, NULL, "s", "0",
     "added to a frame's timestamp to put it on the rails' clock"},

    {"specimen", "name", RIG_KEY_TEXT, OFF(specimen.name), SZ(specimen.name), 1, 63, 0, RIG,
     NULL, "-", "the scene file's name (mock, replay)", "the specimen's label in the store"},
    {"specimen", "material", RIG_KEY_TEXT, OFF(specimen.material), SZ(specimen.material), 1, 63,
     0, 0, NULL, "-", "not recorded", "material, e.g. PET"},
    {"specimen", "crease_angle_left_deg", RIG_KEY_DOUBLE, OFF(specimen.crease_angle_left_deg), 0,
     0.0, 180.0, MAXO, 0, NULL, "deg", "not measured",
     "measured angle (magnitude) of the crease near the clamp at x = 0; replaces the scene's "
     "(folds.angle_left_deg) in the trial's prediction"},
    {"specimen", "crease_angle_right_deg", RIG_KEY_DOUBLE, OFF(specimen.crease_angle_right_deg),
     0, 0.0, 180.0, MAXO, 0, NULL, "deg", "not measured",
     "measured angle (magnitude) of the other crease; replaces the scene's (folds.angle_right_deg) in the "
     "trial's prediction"},
    {"specimen", "crease_position_left", RIG_KEY_DOUBLE, OFF(specimen.crease_position_left), 0, 0.0,
     1.0, MINO | MAXO, 0, NULL, "1", "not measured",
     "measured position of the crease near the clamp at x = 0, a fraction of the free length; replaces the "
     "scene's (folds.position_left) in the trial's prediction"},
    {"specimen", "crease_position_right", RIG_KEY_DOUBLE, OFF(specimen.crease_position_right), 0,
     0.0, 1.0, MINO | MAXO, 0, NULL, "1", "not measured",
     "measured position of the other crease, a fraction of the free length (more than "
     "crease_position_left); replaces the scene's (folds.position_right) in the trial's prediction"},
    {"specimen", "folded_at", RIG_KEY_TEXT, OFF(specimen.folded_at), SZ(specimen.folded_at), 1, 63,
     0, 0, NULL, "-", "not recorded",
     "when the creases were folded: ISO 8601 date-time with a zone (2026-11-30T14:05Z, "
     "2026-11-30T15:05+01:00), not in the future; each trial stores the creases' age"},
    {"specimen", "crease_orientation", RIG_KEY_ENUM, OFF(specimen.crease_orientation), 0, 0, 0,
     ENUM1, 0, crease_names, "-", "not recorded",
     "up or down (toward or away from the surface normal); must match the sign of each of the scene's "
     "creases (folds.angle_left_deg / angle_right_deg, else folds.angle_deg)"},
    {"specimen", "min_clamp_gap_mm", RIG_KEY_DOUBLE, OFF(specimen.min_clamp_gap_mm), 0, 0.0, 1e6,
     0, RIG, NULL, "mm", "0 (mock, replay)",
     "the clamps never come closer; pushed into the compression rail's min_gap_mm"},

    {"camera", "source", RIG_KEY_SOURCE, OFF(camera), 0, 0, 0, 0, RIG, NULL, "-",
     "synthetic (mock)",
     "rig: a V4L2 index (0), a device path (/dev/video0), or aravis:DEVICE-ID for a GigE Vision / "
     "USB3 Vision camera (aravis: = the first one; ribbonctl cameras lists them); mock: synthetic; "
     "replay: not used (replay.video)"},
    {"camera", "fps", RIG_KEY_DOUBLE, OFF(camera.fps), 0, 0.0, 1000.0, MINO, 0, NULL, "1/s", "30",
     "frame rate asked of the camera, or of the synthetic renderer"},
    {"camera", "width_px", RIG_KEY_INT, OFF(camera.width_px), 0, 0, 16384, 0, 0, NULL, "px",
     "0 (device or renderer default)", "frame width"},
    {"camera", "height_px", RIG_KEY_INT, OFF(camera.height_px), 0, 0, 16384, 0, 0, NULL, "px",
     "0 (device or renderer default)", "frame height"},
    {"camera", "calibration", RIG_KEY_PATH, OFF(camera.calibration), SZ(camera.calibration), 0, 0,
     0, RIG, NULL, "-",
     "required in rig mode, and in replay without source_trial; mock: from the synthetic camera",
     "camera calibration file (ribbonctl track --save-calib), relative to the rig file's "
     "directory; replay with source_trial: the source trial's when left out"},
    {"camera", "roi", RIG_KEY_ROI, OFF(camera), 0, 0, 0, 0, 0, NULL, "px", "auto",
     "crop of the saved video: auto (ribbon and clamps plus margin_px), full, or x,y,w,h"},
    {"camera", "margin_px", RIG_KEY_INT, OFF(camera.margin_px), 0, 0, 4096, 0, 0, NULL, "px",
     "20", "margin around ribbon and clamps for roi = auto"},
    {"camera", "video_dir", RIG_KEY_PATH, OFF(camera.video_dir), SZ(camera.video_dir), 0, 0, OUT,
     0, NULL, "-", "videos", "directory of the trial videos (FFV1), relative to rig.outputs"},
    {"camera", "offset_x_px", RIG_KEY_INT, OFF(camera.offset_x_px), 0, -1, 16384, 0, 0, NULL, "px",
     "-1 (the camera's own)", "aravis cameras: OffsetX of the region on the sensor"},
    {"camera", "offset_y_px", RIG_KEY_INT, OFF(camera.offset_y_px), 0, -1, 16384, 0, 0, NULL, "px",
     "-1 (the camera's own)", "aravis cameras: OffsetY of the region on the sensor"},
    {"camera", "exposure_us", RIG_KEY_DOUBLE, OFF(camera.exposure_us), 0, 0.0, 1e7, 0, 0, NULL, "us",
     "0 (the camera's own)", "aravis cameras: ExposureTime; V4L2 cameras: exposure_time_absolute in whole 100 us "
     "units, auto exposure switched off (docs/rig-camera-timing-and-faults.md)"},
    {"camera", "gain_db", RIG_KEY_DOUBLE, OFF(camera.gain_db), 0, -1.0, 100.0, 0, 0, NULL, "dB",
     "-1 (the camera's own)", "aravis cameras: Gain (a V4L2 camera refuses it: see v4l2_gain)"},
    {"camera", "v4l2_gain", RIG_KEY_DOUBLE, OFF(camera.v4l2_gain), 0, -1.0, 1e9, 0, 0, NULL, "-",
     "-1 (the camera's own)", "V4L2 cameras: the gain (else analogue_gain) control, a whole number in the "
     "control's own units, auto gain switched off"},
    {"camera", "ring_frames", RIG_KEY_INT, OFF(camera.ring_frames), 0, 4, 4096, 0, 0, NULL, "frames",
     "64", "rig mode: frames the capture ring holds; the video drops frames (counted) only when its "
           "writer is this far behind"},
    {"camera", "track_max_lag", RIG_KEY_INT, OFF(camera.track_max_lag), 0, 1, 4095, 0, 0, NULL,
     "frames", "16", "rig mode: when the trial loop is more than this many frames behind the camera, "
                      "frames are stored untracked (counted) until it catches up; below ring_frames"},
    {"camera", "frozen_frames", RIG_KEY_INT, OFF(camera.frozen_frames), 0, 2, 100000, 0, 0, NULL, "frames", "12",
     "rig mode: this many identical frames in a row (the same pixels or camera id) while a rail moved "
     "camera.frozen_move_mm since the first of them end the trial failed (a frozen image)"},
    {"camera", "frozen_move_mm", RIG_KEY_DOUBLE, OFF(camera.frozen_move_mm), 0, 0.0, 1000.0, MINO, 0, NULL, "mm",
     "0.05", "rig mode: the rail motion during camera.frozen_frames identical frames that makes them a frozen "
             "image (a still scene repeats legitimately)"},
    {"camera", "time_offset", RIG_KEY_ENUM, OFF(camera.time_offset_measure), 0, 0, 0, 0, 0, time_offset_names, "-",
     "configured", "rig mode: the camera's time offset measured at each shear's start is used for the rest of "
                   "that trial (measure), or only compared with calibration.camera_time_offset_s, with a "
                   "warning when they differ by more than a frame period (configured)"},
    {"camera", "time_offset_window_s", RIG_KEY_DOUBLE, OFF(camera.time_offset_window_s), 0, 0.0, 60.0, 0, 0, NULL,
     "s", "4", "rig mode: the span of each shear's start over which the camera's time offset is measured (the "
                 "shear clamp's image against the shear rail); 0 = not measured"},
    {"camera", "transcode", RIG_KEY_ENUM, OFF(camera.transcode), 0, 0, 0, 0, 0, transcode_names, "-", "ffv1",
     "rig mode: after each trial, in the background, the raw Y800 video (trial-N.avi) is transcoded to "
     "lossless FFV1 (trial-N.mkv), verified bit for bit, and the raw file removed; off: keep the raw video"},
    {"camera", "transcode_keep", RIG_KEY_ENUM, OFF(camera.transcode_keep), 0, 0, 0, 0, 0, keep_names, "-",
     "recorded", "what the transcoded video keeps: recorded (every recorded pixel) or tracker (only the "
                 "tracker's region: ribbon and clamps at the trial's compression plus margin_px, of a video "
                 "recorded with roi = full or x,y,w,h)"},
    {"camera", "transcode_threads", RIG_KEY_INT, OFF(camera.transcode_threads), 0, 1, 16, 0, 0, NULL, "threads",
     "2", "rig mode: the FFV1 encoder's slice threads (they and the worker run in SCHED_IDLE beside the next trial)"},
    {"camera", "noise_sigma", RIG_KEY_DOUBLE, OFF(camera.noise_sigma), 0, 0.0, 255.0, 0, 0, NULL,
     "grey", "2", "mock: additive Gaussian noise of the rendered frames"},
    {"camera", "blur_sigma_px", RIG_KEY_DOUBLE, OFF(camera.blur_sigma_px), 0, 0.0, 100.0, 0, 0,
     NULL, "px", "0.8", "mock: Gaussian optical blur of the rendered frames"},

    {"detect", "dz_jump", RIG_KEY_DOUBLE, OFF(detect.dz_jump), 0, 0.0, 2.0, MINO, 0, NULL, "1",
     "0.02", "jump of Delta Z between consecutive frames that counts as the snap"},
    {"detect", "min_quality", RIG_KEY_DOUBLE, OFF(detect.min_quality), 0, 0.0, 1.0, 0, 0, NULL,
     "1", "0.3", "frames tracked below this quality (0..1) count as not measured"},
    {"detect", "torque_witness", RIG_KEY_ENUM, OFF(detect.torque_witness), 0, 0, 0, SWITCH, 0,
     off_on, "-", "off",
     "on: the shear drive's load (torque, following error; mock: the twin's shear force) is a second snap witness (Modbus shear rail with reg_load, or mock)"},
    {"detect", "load_jump", RIG_KEY_DOUBLE, OFF(detect.load_jump), 0, 0.0, 10.0, MINO, 0, NULL, "1",
     "0.5",
     "witness: a jump of the shear load between consecutive readings above this fraction of the load range seen so far in the shear"},

    {"sim", "target_error", RIG_KEY_DOUBLE, OFF(sim.target_error), 0, 0.0, 0.5, MINO, 0, NULL,
     "1", "0.01",
     "relative error on the snap Delta W the prediction must meet (cheapest ladder rung)"},
    {"sim", "nodes", RIG_KEY_INT, OFF(sim.nodes), 0, 5, 100001, 0, 0, NULL, "1", "from the ladder",
     "explicit N (with sim.dt, wins over target_error; the other one from the scene)"},
    {"sim", "dt", RIG_KEY_DOUBLE, OFF(sim.dt), 0, 0.0, 10.0, MINO, 0, NULL, "s", "from the ladder",
     "explicit time step (wins over target_error)"},
    {"sim", "fast", RIG_KEY_ENUM, OFF(sim.fast), 0, 0, 0, SWITCH, 0, off_on, "-", "on",
     "adaptive step control (README \"Fast mode\", phase 2 from Delta W = 0; every step is kept)"},
    {"sim", "ladder_nodes", RIG_KEY_LIST, OFF(sim), 0, 5, 100001, 0, 0, NULL, "1",
     "39,75,147,291",
     "N of each rung, increasing; dt scales with the edge length, the finest rung at the scene's dt"},
    {"sim", "fit", RIG_KEY_ENUM, OFF(sim.fit), 0, 0, 0, SWITCH, 0, off_on, "-", "on",
     "the calibrated prediction: the trial's strip fitted to its own compression and hold, its snap predicted (docs/calibration.md)"},
    {"sim", "fit_keys", RIG_KEY_TEXT, OFF(sim.fit_keys), SZ(sim.fit_keys), 1, 255, 0, 0, NULL, "-",
     "both crease angles (and folds.hinge_stiffness when compliant)",
     "comma-separated fit parameters; a name that is not one is the trial's named fit failure"},
    {"sim", "fit_refresh_s", RIG_KEY_DOUBLE, OFF(sim.fit_refresh_s), 0, 0.0, 3600.0, 0, 0, NULL, "s", "0.5",
     "trial time between refreshes of the fit during the shear (0: none)"},
    {"sim", "fit_shape", RIG_KEY_ENUM, OFF(sim.fit_shape), 0, 0, 0, SWITCH, 0, off_on, "-", "on",
     "the fit beside a trial also takes the tracked centreline at 4 compression and hold frames before the shear (its refreshes leave them out; docs/calibration.md)"},
    {"sim", "fit_hinge", RIG_KEY_DOUBLE, OFF(sim.fit_hinge), 0, 0.0, 1e6, 0, 0, NULL, "N m/rad", "0",
     "the fit's crease hinges when the scene's creases are rigid: compliant of this stiffness, the fit's start and its prior's centre (0: the scene's rigid creases; docs/calibration.md)"},
    {"sim", "specimen_fit", RIG_KEY_ENUM, OFF(sim.specimen_fit), 0, 0, 0, SWITCH, 0, off_on, "-", "on",
     "after each done trial of a named specimen, its strip refitted from all its finished trials; its next trial predicts with it (off: neither; docs/campaign.md)"},

    {"store", "path", RIG_KEY_PATH, OFF(store_path), SZ(store_path), 0, 0, OUT, ALL, NULL, "-",
     "required", "SQLite database, relative to rig.outputs"},

    {"api", "listen", RIG_KEY_TEXT, OFF(api.listen), SZ(api.listen), 1, 63, 0, 0, NULL, "-",
     "127.0.0.1", "address of the HTTP API: IPv4, IPv6 or localhost"},
    {"api", "port", RIG_KEY_INT, OFF(api.port), 0, 0, 65535, 0, 0, NULL, "1", "8377",
     "TCP port (0 = any free port)"},
    {"api", "token", RIG_KEY_TEXT, OFF(api.token), SZ(api.token), RIG_TOKEN_MIN_LEN, 127, 0, 0,
     NULL, "-", "none", "bearer token, at least 16 characters; required off loopback"},

    {"replay", "video", RIG_KEY_PATH, OFF(replay.video), SZ(replay.video), 0, 0, 0, 0, NULL, "-",
     "the source trial's", "recorded video, relative to the rig file's directory"},
    {"replay", "rails", RIG_KEY_PATH, OFF(replay.rails), SZ(replay.rails), 0, 0, 0, 0, NULL, "-",
     "the source trial's samples", "CSV of rail readings t_s,compress_mm,shear_mm (header line)"},
    {"replay", "source_trial", RIG_KEY_ID, OFF(replay.source_trial), 0, 1, 9.2e18, 0, 0, NULL,
     "-", "none", "id of the recorded trial in the store; the result links to it"},
};

#define N_KEYS (sizeof rig_keys / sizeof rig_keys[0])

/* Keys a rig file may no longer set. A retired key is refused with why and what replaces it,
 * never ignored: a file that sets it was written for a behaviour the program does not have.
 *   detect.jump_fraction: documented as "... and at least this fraction of the trial's Delta Z
 *   range" but never read. The snap is the simulator's (snap_detect.h: speed above snap.speed,
 *   jump above detect.dz_jump, a floor over the tracker's noise); a per-frame jump as a fraction
 *   of the range would depend on the camera's frame rate (a 20 ms snap spans 1 frame at 60 fps,
 *   10 at 500 fps) and the measured snap would no longer be the quantity the simulator predicts. */
static const struct retired_key {
    const char *section, *name, *why;
} retired_keys[] = {
    {"detect", "jump_fraction",
     "retired: snap detection never read it and does not (a jump as a fraction of the Delta Z range "
     "depends on the frame rate); the snap is snap.speed and detect.dz_jump (docs/trials.md \"Snap "
     "detection\"): delete the line"},
};

static const char *retired_why(const char *section, const char *name)
{
    for (size_t i = 0; i < sizeof retired_keys / sizeof retired_keys[0]; i++)
        if (!strcmp(retired_keys[i].section, section) && !strcmp(retired_keys[i].name, name))
            return retired_keys[i].why;
    return NULL;
}

static const char *const section_list[] = {"rig",      "rail.compress", "rail.shear", "trial",
                                           "calibration", "specimen",   "camera",     "detect",
                                           "sim",      "store",         "api",        "replay",
                                           "twin",     NULL};
#define N_SECTIONS (sizeof section_list / sizeof section_list[0] - 1)
#define SEC_RAIL_COMPRESS 1
#define SEC_RAIL_SHEAR 2
#define SEC_TWIN 12

static const cfg_key_table key_table = CFG_KEY_TABLE(rig_keys, rig_key);

const rig_key *rig_config_keys(size_t *n)
{
    if (n) *n = N_KEYS;
    return rig_keys;
}

const char *const *rig_config_sections(void)
{
    return section_list;
}

const char *rig_mode_name(rig_mode m)
{
    return (unsigned)m < 3 ? mode_names[m] : "?";
}

/* ---- load context ------------------------------------------------------------------------ */

/* Where a value came from: a line of the file, an override (1 + its index), or neither. */
typedef struct origin {
    int line;
    int override;
} origin;

/* One line of a rail section (or a rail override), kept to be applied in order. */
typedef struct rail_entry {
    char key[40];
    char value[CFG_INI_MAX_LINE + 1];
    origin from;
} rail_entry;

#define RAIL_ENTRIES_MAX 96

typedef struct rail_lines {
    rail_entry e[RAIL_ENTRIES_MAX];
    int n;
    int file_keys; /* entries from the file */
} rail_lines;

typedef struct load_ctx {
    const char *name;   /* file name for errors */
    const char *const *overrides;
    int lines;          /* lines in the file */
    int section_line[N_SECTIONS];
    origin from[N_KEYS];
    rig_config cfg;
    rail_lines rails[2]; /* compress, shear */
    const char *scene_ovr[64];
    int n_scene_ovr;
    origin twin_from[RIG_TWIN_KEYS_MAX]; /* where each cfg.twin.keys[i] came from */
    cfg_error *err;
} load_ctx;

static int find_section(const char *s)
{
    return cfg_names_find(section_list, N_SECTIONS, s);
}

static int is_scene_section(const char *section)
{
    size_t n;
    const cfg_scene_key *k = cfg_scene_keys(&n);
    for (size_t i = 0; i < n; i++)
        if (strcmp(k[i].section, section) == 0) return 1;
    return 0;
}

/* Fail at a known origin (line, override or default) with key `dotted`. */
static cfg_status fail_from(load_ctx *c, cfg_status st, origin from, const char *dotted,
                            const char *fmt, ...) __attribute__((format(printf, 5, 6)));
static cfg_status fail_from(load_ctx *c, cfg_status st, origin from, const char *dotted,
                            const char *fmt, ...)
{
    char msg[sizeof c->err->message];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    const char *ovr = NULL;
    if (from.override) {
        ovr = c->overrides[from.override - 1];
        if (!ovr) ovr = ""; /* a NULL override is still an override */
    }
    return cfg_error_from(c->err, st, c->name, from.line, ovr, dotted, msg);
}

/* Fail blaming table key `dotted` where it was last set. */
static cfg_status fail_key(load_ctx *c, cfg_status st, const char *dotted, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static cfg_status fail_key(load_ctx *c, cfg_status st, const char *dotted, const char *fmt, ...)
{
    char msg[sizeof c->err->message];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    int k = cfg_keys_find_dotted(&key_table, dotted);
    origin from = {0, 0};
    if (k >= 0) from = c->from[k];
    return fail_from(c, st, from, dotted, "%s", msg);
}

/* Where rail key `key` of rail r was last set ({0,0}: the driver's default). */
static origin rail_origin(const load_ctx *c, int r, const char *key)
{
    origin from = {0, 0};
    for (int i = 0; i < c->rails[r].n; i++)
        if (strcmp(c->rails[r].e[i].key, key) == 0) from = c->rails[r].e[i].from;
    return from;
}

static const char *rail_name(int r)
{
    return r == 0 ? "compress" : "shear";
}

static cfg_status fail_rail(load_ctx *c, cfg_status st, int r, const char *key, const char *fmt,
                            ...) __attribute__((format(printf, 5, 6)));
static cfg_status fail_rail(load_ctx *c, cfg_status st, int r, const char *key, const char *fmt,
                            ...)
{
    char msg[sizeof c->err->message], dotted[96];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    snprintf(dotted, sizeof dotted, "rail.%s.%s", rail_name(r), key);
    origin from = rail_origin(c, r, key);
    if (!from.line && !from.override) {
        /* A driver default: name the section header, the place to add the key. */
        from.line = c->section_line[r == 0 ? SEC_RAIL_COMPRESS : SEC_RAIL_SHEAR];
    }
    return fail_from(c, st, from, dotted, "%s", msg);
}

/* ---- values --------------------------------------------------------------------------------- */

static const char *skip_space(const char *p)
{
    while (*p && isspace((unsigned char)*p)) p++;
    return p;
}

static void range_text(const rig_key *k, char *buf, size_t len)
{
    cfg_range_text(buf, len, k->min, k->max, (k->flags & MINO) != 0, (k->flags & MAXO) != 0,
                   k->unit);
}

static int in_range(const rig_key *k, double v)
{
    return cfg_in_range(v, k->min, k->max, (k->flags & MINO) != 0, (k->flags & MAXO) != 0);
}

/* One finite number; the whole of `value` must be used. */
static cfg_status parse_double(const char *value, double *out, char *msg, size_t len)
{
    char shown[64];
    const char *end;
    double v;
    cfg_text_printable(shown, sizeof shown, value, strlen(value));
    cfg_number_status ns = cfg_number_scan(value, &v, &end);
    if (ns) {
        snprintf(msg, len, "'%s' %s", shown, cfg_number_why(ns));
        return CFG_ERR_VALUE;
    }
    if (*skip_space(end)) {
        snprintf(msg, len, "unexpected text after the number in '%s' (values carry no unit)",
                 shown);
        return CFG_ERR_VALUE;
    }
    *out = v;
    return CFG_OK;
}

/* One decimal integer (optionally signed), whole value. */
static cfg_status parse_integer(const char *value, long long *out, char *msg, size_t len)
{
    char shown[64];
    char *end;
    cfg_text_printable(shown, sizeof shown, value, strlen(value));
    errno = 0;
    long long v = strtoll(value, &end, 10);
    if (end == value) {
        snprintf(msg, len, "'%s' is not an integer", shown);
        return CFG_ERR_VALUE;
    }
    if (*end == '.' || *end == 'e' || *end == 'E' || *end == 'x' || *end == 'X') {
        snprintf(msg, len, "'%s' is not an integer (whole decimal numbers only)", shown);
        return CFG_ERR_VALUE;
    }
    if (*skip_space(end)) {
        snprintf(msg, len, "unexpected text after the number in '%s'", shown);
        return CFG_ERR_VALUE;
    }
    if (errno == ERANGE) {
        snprintf(msg, len, "'%s' is too large", shown);
        return CFG_ERR_RANGE;
    }
    *out = v;
    return CFG_OK;
}

static cfg_status printable_text(const char *value, size_t len_min, size_t len_max, char *msg,
                                 size_t len)
{
    size_t n = strlen(value);
    for (size_t i = 0; i < n; i++) {
        unsigned char ch = (unsigned char)value[i];
        if (ch < 0x20 || ch >= 0x7f) {
            snprintf(msg, len, "character %zu is not printable ASCII", i + 1);
            return CFG_ERR_VALUE;
        }
    }
    if (n < len_min || n > len_max) {
        snprintf(msg, len, "%zu characters: allowed %zu to %zu", n, len_min, len_max);
        return CFG_ERR_RANGE;
    }
    return CFG_OK;
}

/* "x,y,w,h" or a list "a,b,c": up to max integers separated by commas (spaces allowed). */
static int parse_int_list(const char *value, long long *out, int max, char *msg, size_t len)
{
    const char *p = value;
    int n = 0;
    for (;;) {
        p = skip_space(p);
        char *end;
        errno = 0;
        long long v = strtoll(p, &end, 10);
        if (end == p || errno == ERANGE) {
            char shown[64];
            cfg_text_printable(shown, sizeof shown, value, strlen(value));
            snprintf(msg, len, "'%s' is not a list of integers separated by commas", shown);
            return -1;
        }
        if (n == max) {
            snprintf(msg, len, "more than %d numbers", max);
            return -1;
        }
        out[n++] = v;
        p = skip_space(end);
        if (*p == '\0') return n;
        if (*p != ',') {
            char shown[64];
            cfg_text_printable(shown, sizeof shown, value, strlen(value));
            snprintf(msg, len, "'%s' is not a list of integers separated by commas", shown);
            return -1;
        }
        p++;
    }
}

/* Parse `value` (trimmed) for key k into cfg. */
/* DOUBLE: a finite number within the key's bounds. */
static cfg_status apply_double(unsigned char *field, const rig_key *k, const char *value, char *msg,
                               size_t len)
{
    char range[96];
    double v;
    cfg_status st = parse_double(value, &v, msg, len);
    if (st) return st;
    if (!in_range(k, v)) {
        range_text(k, range, sizeof range);
        snprintf(msg, len, "%.10g is out of range: allowed %s (%s)", v, range, k->doc);
        return CFG_ERR_RANGE;
    }
    memcpy(field, &v, sizeof v);
    return CFG_OK;
}

/* INT and ID: an integer within the key's bounds, stored as int or int64_t. */
static cfg_status apply_integer(unsigned char *field, const rig_key *k, const char *value,
                                const char *shown, char *msg, size_t len)
{
    char range[96];
    long long v;
    cfg_status st = parse_integer(value, &v, msg, len);
    if (st) return st;
    if (!in_range(k, (double)v)) {
        range_text(k, range, sizeof range);
        snprintf(msg, len, "%s is out of range: allowed integer %s (%s)", shown, range, k->doc);
        return CFG_ERR_RANGE;
    }
    if (k->type == RIG_KEY_INT) {
        int iv = (int)v;
        memcpy(field, &iv, sizeof iv);
    } else {
        int64_t iv = v;
        memcpy(field, &iv, sizeof iv);
    }
    return CFG_OK;
}

/* SIGN: +1 or -1. */
static cfg_status apply_sign(unsigned char *field, const rig_key *k, const char *value,
                             const char *shown, char *msg, size_t len)
{
    int s = 0;
    if (strcmp(value, "1") == 0 || strcmp(value, "+1") == 0) s = 1;
    if (strcmp(value, "-1") == 0) s = -1;
    if (!s) {
        snprintf(msg, len, "'%s' is not +1 or -1 (%s)", shown, k->doc);
        return CFG_ERR_VALUE;
    }
    memcpy(field, &s, sizeof s);
    return CFG_OK;
}

/* ENUM: one of the key's names (stored as its index, from 1 with ENUM1, or as a bool for a
 * SWITCH). */
static cfg_status apply_enum(unsigned char *field, const rig_key *k, const char *value,
                             const char *shown, char *msg, size_t len)
{
    for (int i = 0; k->names[i]; i++) {
        if (strcmp(value, k->names[i]) == 0) {
            if (k->flags & SWITCH) {
                bool b = i == 1;
                memcpy(field, &b, sizeof b);
            } else {
                int v = (k->flags & ENUM1) ? i + 1 : i;
                memcpy(field, &v, sizeof v);
            }
            return CFG_OK;
        }
    }
    char allowed[96];
    cfg_names_join(k->names, allowed, sizeof allowed);
    snprintf(msg, len, "'%s' is not one of: %s", shown, allowed);
    return CFG_ERR_VALUE;
}

/* LIST: the simulator's ladder, increasing integers within the key's bounds. */
static cfg_status apply_ladder(unsigned char *field, const rig_key *k, const char *value, char *msg,
                               size_t len)
{
    char range[96];
    long long v[RIG_LADDER_MAX];
    int n = parse_int_list(value, v, RIG_LADDER_MAX, msg, len);
    if (n < 0) return CFG_ERR_VALUE;
    rig_sim *sim = (rig_sim *)field;
    for (int i = 0; i < n; i++) {
        if (!in_range(k, (double)v[i])) {
            range_text(k, range, sizeof range);
            snprintf(msg, len, "rung %d (%lld) is out of range: allowed integer %s each", i + 1,
                     v[i], range);
            return CFG_ERR_RANGE;
        }
        if (i > 0 && v[i] <= v[i - 1]) {
            snprintf(msg, len, "rung %d (%lld) is not larger than the one before (%lld)", i + 1,
                     v[i], v[i - 1]);
            return CFG_ERR_VALUE;
        }
    }
    for (int i = 0; i < n; i++) sim->ladder_nodes[i] = (int)v[i];
    sim->n_ladder = n;
    return CFG_OK;
}

/* ROI: auto, full or x,y,w,h in pixels. */
static cfg_status apply_roi(unsigned char *field, const char *value, const char *shown, char *msg,
                            size_t len)
{
    rig_camera *cam = (rig_camera *)field;
    if (strcmp(value, "auto") == 0 || strcmp(value, "full") == 0) {
        cam->roi = value[0] == 'a' ? RIG_ROI_AUTO : RIG_ROI_FULL;
        return CFG_OK;
    }
    long long v[4];
    int n = parse_int_list(value, v, 4, msg, len);
    if (n != 4) {
        snprintf(msg, len, "'%s' is not auto, full or x,y,w,h (pixels)", shown);
        return CFG_ERR_VALUE;
    }
    if (v[0] < 0 || v[1] < 0 || v[2] < 1 || v[3] < 1 || v[0] + v[2] > 16384 ||
        v[1] + v[3] > 16384) {
        snprintf(msg, len, "'%s': x, y >= 0, w, h >= 1, and the box inside 16384 px", shown);
        return CFG_ERR_RANGE;
    }
    cam->roi = RIG_ROI_RECT;
    cam->roi_x = (int)v[0];
    cam->roi_y = (int)v[1];
    cam->roi_w = (int)v[2];
    cam->roi_h = (int)v[3];
    return CFG_OK;
}

/* SOURCE: a device index, a /dev/ path or synthetic (checked per mode later). */
static cfg_status apply_source(unsigned char *field, const char *value, const char *shown, char *msg,
                               size_t len)
{
    rig_camera *cam = (rig_camera *)field;
    if (strcmp(value, "synthetic") == 0) {
        cam->source = RIG_SOURCE_SYNTHETIC;
        return CFG_OK;
    }
    if (isdigit((unsigned char)value[0])) {
        long long v;
        cfg_status st = parse_integer(value, &v, msg, len);
        if (st) return st;
        if (v < 0 || v > 255) {
            snprintf(msg, len, "device index %s is out of range: allowed 0 to 255", shown);
            return CFG_ERR_RANGE;
        }
        cam->source = RIG_SOURCE_INDEX;
        cam->index = (int)v;
        return CFG_OK;
    }
    if (strncmp(value, "/dev/", 5) == 0 && value[5]) {
        cfg_status st = printable_text(value, 6, sizeof cam->device - 1, msg, len);
        if (st) return st;
        cam->source = RIG_SOURCE_DEVICE;
        snprintf(cam->device, sizeof cam->device, "%s", value);
        return CFG_OK;
    }
    if (strncmp(value, "aravis:", 7) == 0) {
        if (value[7]) {
            cfg_status st = printable_text(value + 7, 1, sizeof cam->device - 1, msg, len);
            if (st) return st;
        }
        cam->source = RIG_SOURCE_ARAVIS;
        snprintf(cam->device, sizeof cam->device, "%s", value + 7);
        return CFG_OK;
    }
    snprintf(msg, len,
             "'%s' is not a device index (0), a device path (/dev/video0), aravis:DEVICE-ID "
             "(aravis: for the first GenICam camera) or synthetic",
             shown);
    return CFG_ERR_VALUE;
}

static cfg_status value_apply(const rig_key *k, const char *value, rig_config *cfg, char *msg,
                              size_t len)
{
    char shown[64];
    unsigned char *field = (unsigned char *)cfg + k->offset;
    cfg_text_printable(shown, sizeof shown, value, strlen(value));
    if (value[0] == '\0') {
        snprintf(msg, len, "empty value");
        return CFG_ERR_VALUE;
    }
    switch (k->type) {
    case RIG_KEY_DOUBLE:
        return apply_double(field, k, value, msg, len);
    case RIG_KEY_INT:
    case RIG_KEY_ID:
        return apply_integer(field, k, value, shown, msg, len);
    case RIG_KEY_SIGN:
        return apply_sign(field, k, value, shown, msg, len);
    case RIG_KEY_ENUM:
        return apply_enum(field, k, value, shown, msg, len);
    case RIG_KEY_TEXT: {
        cfg_status st = printable_text(value, (size_t)k->min, (size_t)k->max, msg, len);
        if (st) return st;
        snprintf((char *)field, k->size, "%s", value);
        return CFG_OK;
    }
    case RIG_KEY_PATH: {
        cfg_status st = printable_text(value, 1, k->size - 1, msg, len);
        if (st) return st;
        if (value[0] == '~') {
            snprintf(msg, len, "'~' is not expanded: write the path in full, or relative");
            return CFG_ERR_VALUE;
        }
        snprintf((char *)field, k->size, "%s", value);
        return CFG_OK;
    }
    case RIG_KEY_LIST:
        return apply_ladder(field, k, value, msg, len);
    case RIG_KEY_ROI:
        return apply_roi(field, value, shown, msg, len);
    case RIG_KEY_SOURCE:
        return apply_source(field, value, shown, msg, len);
    }
    snprintf(msg, len, "internal error: key of unknown type");
    return CFG_ERR_VALUE;
}

/* ---- the file -------------------------------------------------------------------------------- */

static int on_section(void *user, int line, const char *section)
{
    load_ctx *c = user;
    if (strlen(section) > 63) {
        cfg_error_set(c->err, CFG_ERR_SYNTAX, CFG_ORIGIN_LINE, c->name, line, NULL, NULL,
                      "section name longer than 63 characters");
        return 1;
    }
    int s = find_section(section);
    if (s < 0) {
        char shown[64];
        cfg_text_printable(shown, sizeof shown, section, strlen(section));
        cfg_error_set(c->err, CFG_ERR_UNKNOWN, CFG_ORIGIN_LINE, c->name, line, NULL, NULL,
                      "unknown section [%s] (known: rig rail.compress rail.shear trial "
                      "calibration specimen camera detect sim store api replay twin)",
                      shown);
        return 1;
    }
    if (!c->section_line[s]) c->section_line[s] = line;
    return 0;
}

/* Validate one rail key on a scratch config and keep it. */
static int rail_keep(load_ctx *c, int r, origin from, const char *key, const char *value)
{
    char dotted[96], why[256];
    snprintf(dotted, sizeof dotted, "rail.%s.%s", rail_name(r), key);
    rail_lines *rl = &c->rails[r];
    if (from.line) {
        for (int i = 0; i < rl->n; i++) {
            if (strcmp(rl->e[i].key, key) == 0) {
                fail_from(c, CFG_ERR_DUPLICATE, from, dotted, "set twice (first on line %d)",
                          rl->e[i].from.line);
                return 1;
            }
        }
    }
    rail_config scratch;
    rail_config_init(&scratch, rail_name(r));
    cfg_status rc = rail_config_set(&scratch, key, value, why, sizeof why);
    if (rc == CFG_ERR_UNKNOWN) {
        fail_from(c, CFG_ERR_UNKNOWN, from, dotted,
                  "unknown key in [rail.%s] (README \"Rig file keys\" lists the rail keys)",
                  rail_name(r));
        return 1;
    }
    if (rc != 0) {
        fail_from(c, CFG_ERR_VALUE, from, dotted, "%s", why);
        return 1;
    }
    if (rl->n == RAIL_ENTRIES_MAX || strlen(key) >= sizeof rl->e[0].key ||
        strlen(value) >= sizeof rl->e[0].value) {
        fail_from(c, CFG_ERR_RANGE, from, dotted, "too many rail keys or too long a value");
        return 1;
    }
    rail_entry *e = &rl->e[rl->n++];
    snprintf(e->key, sizeof e->key, "%s", key);
    snprintf(e->value, sizeof e->value, "%s", value);
    e->from = from;
    if (from.line) rl->file_keys++;
    return 0;
}

/* Whether "section.key" is a scene key (the scene loader's table). */
static int is_scene_key(const char *dotted)
{
    size_t n;
    const cfg_scene_key *k = cfg_scene_keys(&n);
    for (size_t i = 0; i < n; i++) {
        size_t ls = strlen(k[i].section);
        if (!strncmp(dotted, k[i].section, ls) && dotted[ls] == '.' && !strcmp(dotted + ls + 1, k[i].name))
            return 1;
    }
    return 0;
}

/* Keep one twin key ("folds.angle_deg", "-86") as "folds.angle_deg=-86", to be applied to the
 * scene once it is loaded (twin_build). Only the name is checked here; the value is the scene
 * loader's to check. Returns 0, or 1 with the error set. */
static int twin_keep(load_ctx *c, origin from, const char *name, const char *value)
{
    char dotted[160];
    snprintf(dotted, sizeof dotted, "twin.%s", name);
    if (!is_scene_key(name)) {
        fail_from(c, CFG_ERR_UNKNOWN, from, dotted,
                  "not a scene key: [twin] takes the scene's keys as SECTION.KEY = VALUE, e.g. "
                  "folds.angle_deg = -86 (docs/config.md \"Scene files\")");
        return 1;
    }
    if (!strcmp(name, "ribbon.length")) {
        /* The runner turns rail positions into Delta L and Delta W with the scene's free length;
         * a twin of another length would be clamped where no rail puts it. */
        fail_from(c, CFG_ERR_CHECK, from, dotted,
                  "the twin's free length is the trial's (the rails' positions become Delta L and Delta W "
                  "with the scene's ribbon.length); set it in the scene");
        return 1;
    }
    if (!strncmp(name, "protocol.", 9)) {
        /* The rails move the twin; the camera and its calibration frame the trial's protocol. */
        fail_from(c, CFG_ERR_CHECK, from, dotted,
                  "the rails drive the twin: its protocol is the trial's (set protocol.* in the scene or "
                  "with --set %s)", name);
        return 1;
    }
    rig_twin *tw = &c->cfg.twin;
    size_t ln = strlen(name);
    if (from.line) {
        for (int i = 0; i < tw->n; i++) {
            if (!strncmp(tw->keys[i], name, ln) && tw->keys[i][ln] == '=') {
                fail_from(c, CFG_ERR_DUPLICATE, from, dotted, "set twice (first on line %d)",
                          c->twin_from[i].line);
                return 1;
            }
        }
    }
    if (tw->n == RIG_TWIN_KEYS_MAX || ln + strlen(value) + 2 > RIG_TWIN_KEY_LEN) {
        fail_from(c, CFG_ERR_RANGE, from, dotted, "too many twin keys (at most %d) or too long a value",
                  RIG_TWIN_KEYS_MAX);
        return 1;
    }
    size_t lv = strlen(value); /* ln + 1 + lv + 1 <= RIG_TWIN_KEY_LEN, checked above */
    memcpy(tw->keys[tw->n], name, ln);
    tw->keys[tw->n][ln] = '=';
    memcpy(tw->keys[tw->n] + ln + 1, value, lv + 1);
    c->twin_from[tw->n++] = from;
    tw->present = true;
    return 0;
}

static int on_key(void *user, int line, const char *section, const char *name, const char *value)
{
    load_ctx *c = user;
    char dotted[160];
    snprintf(dotted, sizeof dotted, "%s.%s", section, name);
    origin from = {line, 0};
    int s = find_section(section);
    if (s < 0) { /* on_section refused it already; inih still reports its keys */
        fail_from(c, CFG_ERR_UNKNOWN, from, dotted, "unknown section [%s]", section);
        return 1;
    }
    if (s == SEC_RAIL_COMPRESS || s == SEC_RAIL_SHEAR)
        return rail_keep(c, s == SEC_RAIL_COMPRESS ? 0 : 1, from, name, value);
    if (s == SEC_TWIN) return twin_keep(c, from, name, value);
    const char *retired = retired_why(section, name);
    if (retired) {
        fail_from(c, CFG_ERR_UNKNOWN, from, dotted, "%s", retired);
        return 1;
    }
    int k = cfg_keys_find(&key_table, section, name);
    if (k < 0) {
        char known[320];
        cfg_keys_known(&key_table, section, known, sizeof known);
        fail_from(c, CFG_ERR_UNKNOWN, from, dotted, "unknown key in [%s] (known: %s)", section,
                  known);
        return 1;
    }
    if (c->from[k].line) {
        fail_from(c, CFG_ERR_DUPLICATE, from, dotted, "set twice (first on line %d)",
                  c->from[k].line);
        return 1;
    }
    char msg[sizeof c->err->message];
    cfg_status st = value_apply(&rig_keys[k], value, &c->cfg, msg, sizeof msg);
    if (st) {
        fail_from(c, st, from, dotted, "%s", msg);
        return 1;
    }
    c->from[k].line = line;
    return 0;
}

/* ---- overrides ------------------------------------------------------------------------------- */

static cfg_status override_apply(load_ctx *c, int index)
{
    const char *ovr = c->overrides[index];
    origin from = {0, index + 1};
    char key[128], value[CFG_INI_MAX_LINE + 1], msg[sizeof c->err->message];
    cfg_split sp = cfg_override_split(ovr, key, sizeof key, value, sizeof value);
    if (sp == CFG_SPLIT_NO_EQUALS || sp == CFG_SPLIT_KEY_TOO_LONG)
        return fail_from(c, CFG_ERR_SYNTAX, from, NULL, "expected section.key=value");
    if (sp == CFG_SPLIT_VALUE_TOO_LONG)
        return fail_from(c, CFG_ERR_VALUE, from, key, "value too long");
    if (!strncmp(key, "twin.", 5)) return twin_keep(c, from, key + 5, value) ? c->err->status : CFG_OK;
    char *dot = strrchr(key, '.');
    if (!dot || dot == key || !dot[1])
        return fail_from(c, CFG_ERR_SYNTAX, from, key, "expected section.key=value");
    *dot = '\0';
    const char *section = key, *name = dot + 1;
    char dotted[sizeof key + 2];
    snprintf(dotted, sizeof dotted, "%s.%s", section, name);
    if (is_scene_section(section)) {
        if (c->n_scene_ovr == (int)(sizeof c->scene_ovr / sizeof c->scene_ovr[0]))
            return fail_from(c, CFG_ERR_RANGE, from, dotted, "too many scene overrides");
        c->scene_ovr[c->n_scene_ovr++] = ovr;
        return CFG_OK;
    }
    int s = find_section(section);
    if (s == SEC_RAIL_COMPRESS || s == SEC_RAIL_SHEAR)
        return rail_keep(c, s == SEC_RAIL_COMPRESS ? 0 : 1, from, name, value) ? c->err->status
                                                                                : CFG_OK;
    const char *retired = retired_why(section, name);
    if (retired) return fail_from(c, CFG_ERR_UNKNOWN, from, dotted, "%s", retired);
    int k = cfg_keys_find(&key_table, section, name);
    if (k < 0)
        return fail_from(c, CFG_ERR_UNKNOWN, from, dotted,
                         "unknown key (README \"Rig files\" lists the keys)");
    cfg_status st = value_apply(&rig_keys[k], value, &c->cfg, msg, sizeof msg);
    if (st) return fail_from(c, st, from, dotted, "%s", msg);
    c->from[k].override = index + 1;
    return CFG_OK;
}

/* ---- required keys --------------------------------------------------------------------------- */

/* A missing key is named at its section's header, or at the last line if the section is absent. */
static cfg_status fail_missing(load_ctx *c, const char *section, const char *dotted,
                               const char *why)
{
    int s = find_section(section);
    int line = (s >= 0 && c->section_line[s]) ? c->section_line[s] : c->lines;
    origin from = {line, 0};
    const char *where = (s >= 0 && c->section_line[s]) ? "from this section" : "(no such section)";
    if (line == 0)
        return cfg_error_set(c->err, CFG_ERR_MISSING, CFG_ORIGIN_FILE, c->name, 0, NULL, dotted,
                             "required key missing (the file is empty)");
    return fail_from(c, CFG_ERR_MISSING, from, dotted, "required key missing %s (%s)", where, why);
}

static cfg_status check_required(load_ctx *c)
{
    unsigned mode_bit = 1u << c->cfg.mode;
    for (size_t i = 0; i < N_KEYS; i++) {
        const rig_key *k = &rig_keys[i];
        if (!(k->required & mode_bit) || c->from[i].line) continue;
        char dotted[96], why[192];
        snprintf(dotted, sizeof dotted, "%s.%s", k->section, k->name);
        snprintf(why, sizeof why, "%s mode: %s", rig_mode_name(c->cfg.mode), k->doc);
        return fail_missing(c, k->section, dotted, why);
    }
    /* Rails: a driver must be named in both sections in rig and mock modes. */
    if (c->cfg.mode != RIG_MODE_REPLAY) {
        for (int r = 0; r < 2; r++) {
            int have = 0;
            for (int i = 0; i < c->rails[r].n; i++)
                if (c->rails[r].e[i].from.line && strcmp(c->rails[r].e[i].key, "driver") == 0)
                    have = 1;
            if (!have) {
                char section[32], dotted[64], why[96];
                snprintf(section, sizeof section, "rail.%s", rail_name(r));
                snprintf(dotted, sizeof dotted, "rail.%s.driver", rail_name(r));
                snprintf(why, sizeof why, "%s mode moves the rails: mock | gcode | modbus",
                         rig_mode_name(c->cfg.mode));
                return fail_missing(c, section, dotted, why);
            }
        }
    }
    return CFG_OK;
}

/* ---- paths ----------------------------------------------------------------------------------- */

/* Lexical normalisation of an absolute path in place: "//" -> "/", "/./" -> "/", "a/../" -> "". */
static void path_normalise(char *p)
{
    char *out = p; /* p[0] == '/' */
    const char *in = p;
    size_t n = 0;
    while (*in) {
        while (*in == '/') in++;
        if (!*in) break;
        const char *seg = in;
        while (*in && *in != '/') in++;
        size_t len = (size_t)(in - seg);
        if (len == 1 && seg[0] == '.') continue;
        if (len == 2 && seg[0] == '.' && seg[1] == '.') {
            while (n > 0 && out[n - 1] != '/') n--;
            if (n > 0) n--; /* the slash before the removed segment */
            continue;
        }
        out[n++] = '/';
        memmove(out + n, seg, len);
        n += len;
    }
    if (n == 0) out[n++] = '/';
    out[n] = '\0';
}

/* dst = base/rel (or rel when absolute), normalised. base is absolute. -1 if too long. */
static int path_join(char *dst, size_t len, const char *base, const char *rel)
{
    int n = rel[0] == '/' ? snprintf(dst, len, "%s", rel) : snprintf(dst, len, "%s/%s", base, rel);
    if (n < 0 || (size_t)n >= len) return -1;
    path_normalise(dst);
    return 0;
}

/* The working directory, or -1. */
static int cwd_get(char *buf, size_t len)
{
    if (!getcwd(buf, len)) return -1;
    return 0;
}

static cfg_status resolve_paths(load_ctx *c, const char *dir)
{
    rig_config *cfg = &c->cfg;
    char cwd[RIG_PATH_MAX];
    if (cwd_get(cwd, sizeof cwd) < 0)
        return cfg_error_set(c->err, CFG_ERR_IO, CFG_ORIGIN_FILE, c->name, 0, NULL, NULL,
                             "cannot read the working directory: %s", strerror(errno));
    if (path_join(cfg->dir, sizeof cfg->dir, cwd, dir && dir[0] ? dir : ".") < 0)
        return cfg_error_set(c->err, CFG_ERR_IO, CFG_ORIGIN_FILE, c->name, 0, NULL, NULL,
                             "the rig file's directory is too long a path");
    const char *out_base = cfg->outputs == RIG_BASE_CWD ? cwd : cfg->dir;
    for (size_t i = 0; i < N_KEYS; i++) {
        const rig_key *k = &rig_keys[i];
        if (k->type != RIG_KEY_PATH) continue;
        char *field = (char *)cfg + k->offset;
        if (!field[0]) continue;
        char tmp[RIG_PATH_MAX];
        snprintf(tmp, sizeof tmp, "%s", field);
        char dotted[96];
        snprintf(dotted, sizeof dotted, "%s.%s", k->section, k->name);
        if (path_join(field, k->size, (k->flags & OUT) ? out_base : cfg->dir, tmp) < 0)
            return fail_key(c, CFG_ERR_RANGE, dotted, "the resolved path is longer than %zu bytes",
                            k->size - 1);
    }
    return CFG_OK;
}

/* ---- the twin -------------------------------------------------------------------------------- */

/* The twin's scene: the trial's scene with the [twin] keys applied in order (file lines, then
 * overrides). An error of a key is named at its line or --set as "twin.section.key"; a check of the
 * whole twin that blames a value it took from the scene is named at the [twin] header. */
static cfg_status twin_build(load_ctx *c)
{
    rig_twin *tw = &c->cfg.twin;
    if (!tw->present) return CFG_OK;
    if (c->cfg.mode == RIG_MODE_REPLAY) {
        origin from = c->twin_from[0];
        return fail_from(c, CFG_ERR_CHECK, from, "twin", "replay mode films no twin (a recorded video and "
                         "rail positions): remove [twin] or use mode = mock");
    }
    const char *texts[RIG_TWIN_KEYS_MAX];
    for (int i = 0; i < tw->n; i++) texts[i] = tw->keys[i];
    cfg_error e;
    if (cfg_scene_apply(&c->cfg.scene, "twin", texts, tw->n, &tw->scene, &e) == CFG_OK) return CFG_OK;
    char dotted[sizeof e.key + 8];
    snprintf(dotted, sizeof dotted, "twin.%s", e.key[0] ? e.key : "?");
    if (e.origin == CFG_ORIGIN_OVERRIDE) {
        for (int i = tw->n - 1; i >= 0; i--)
            if (!strcmp(e.where, tw->keys[i])) return fail_from(c, e.status, c->twin_from[i], dotted, "%s", e.message);
    }
    origin at = {c->section_line[SEC_TWIN], 0};
    if (!at.line) at = c->twin_from[0];
    return fail_from(c, e.status, at, dotted, "the twin's scene (the trial's scene with [twin] applied): %s",
                     e.message);
}

/* ---- rails ----------------------------------------------------------------------------------- */

static cfg_status rails_build(load_ctx *c)
{
    rig_config *cfg = &c->cfg;
    int need = cfg->mode != RIG_MODE_REPLAY;
    int present = c->section_line[SEC_RAIL_COMPRESS] || c->section_line[SEC_RAIL_SHEAR] ||
                  c->rails[0].n || c->rails[1].n;
    if (!need && !present) return CFG_OK;
    for (int r = 0; r < 2; r++) {
        rail_config *rc = r == 0 ? &cfg->compress : &cfg->shear;
        rail_lines *rl = &c->rails[r];
        rail_config_init(rc, rail_name(r));
        char why[700], key[48];
        /* The preset (or map file) first, then everything else in order: file lines, then
           overrides. */
        for (int pass = 0; pass < 2; pass++) {
            for (int i = 0; i < rl->n; i++) {
                int is_map = strcmp(rl->e[i].key, "map") == 0;
                if (is_map != (pass == 0)) continue;
                if (rail_config_set_in(rc, rl->e[i].key, rl->e[i].value, cfg->dir, why, sizeof why) != 0)
                    return fail_rail(c, CFG_ERR_VALUE, r, rl->e[i].key, "%s", why);
            }
        }
        if (!c->section_line[r == 0 ? SEC_RAIL_COMPRESS : SEC_RAIL_SHEAR] && !rl->n) {
            char section[32], dotted[64];
            snprintf(section, sizeof section, "rail.%s", rail_name(r));
            snprintf(dotted, sizeof dotted, "rail.%s.driver", rail_name(r));
            return fail_missing(c, section, dotted, "replay mode: both rail sections or neither");
        }
        if (rail_config_check(rc, why, sizeof why, key, sizeof key) != 0)
            return fail_rail(c, CFG_ERR_CHECK, r, key[0] ? key : "driver", "%s", why);
    }
    cfg->has_rails = true;
    return CFG_OK;
}

/* ---- mode rules and cross-checks -------------------------------------------------------------- */

/* localhost, 127.0.0.0/8, ::1 and ::ffff:127.x.x.x. */
static int is_loopback(const char *addr)
{
    if (strcmp(addr, "localhost") == 0) return 1;
    struct in_addr a4;
    if (inet_pton(AF_INET, addr, &a4) == 1) return (ntohl(a4.s_addr) >> 24) == 127;
    struct in6_addr a6;
    if (inet_pton(AF_INET6, addr, &a6) == 1)
        return IN6_IS_ADDR_LOOPBACK(&a6) || (IN6_IS_ADDR_V4MAPPED(&a6) && a6.s6_addr[12] == 127);
    return 0;
}

static int is_address(const char *addr)
{
    unsigned char buf[sizeof(struct in6_addr)];
    return strcmp(addr, "localhost") == 0 || inet_pton(AF_INET, addr, buf) == 1 ||
           inet_pton(AF_INET6, addr, buf) == 1;
}

static int key_set(const load_ctx *c, const char *dotted)
{
    int k = cfg_keys_find_dotted(&key_table, dotted);
    return k >= 0 && (c->from[k].line || c->from[k].override);
}

static cfg_status check_mode(load_ctx *c)
{
    rig_config *cfg = &c->cfg;
    rig_mode m = cfg->mode;

    if (!key_set(c, "rig.clock")) cfg->clock = m == RIG_MODE_MOCK ? RIG_CLOCK_VIRTUAL : RIG_CLOCK_REAL;
    if (cfg->clock == RIG_CLOCK_VIRTUAL && m != RIG_MODE_MOCK)
        return fail_key(c, CFG_ERR_CHECK, "rig.clock",
                        "virtual is for mock mode only: %s mode runs on the real clock",
                        rig_mode_name(m));

    if (cfg->has_rails && m != RIG_MODE_REPLAY) {
        for (int r = 0; r < 2; r++) {
            const rail_config *rc = r == 0 ? &cfg->compress : &cfg->shear;
            int mock = strcmp(rc->driver, "mock") == 0;
            if (m == RIG_MODE_MOCK && !mock)
                return fail_rail(c, CFG_ERR_CHECK, r, "driver",
                                 "mock mode uses mock rails (driver = mock), not '%s'", rc->driver);
            if (m == RIG_MODE_RIG && mock)
                return fail_rail(c, CFG_ERR_CHECK, r, "driver",
                                 "rig mode drives real rails (gcode or modbus); use mode = mock "
                                 "for mock rails");
        }
    }

    /* Camera source. */
    rig_camera *cam = &cfg->camera;
    if (m == RIG_MODE_RIG && cam->source == RIG_SOURCE_SYNTHETIC)
        return fail_key(c, CFG_ERR_CHECK, "camera.source",
                        "rig mode needs a camera: a device index (0), a path (/dev/video0) or "
                        "aravis:DEVICE-ID");
    if (cam->track_max_lag >= cam->ring_frames)
        return fail_key(c, CFG_ERR_CHECK, "camera.track_max_lag",
                        "%d must be below camera.ring_frames (%d)", cam->track_max_lag, cam->ring_frames);
    if (m == RIG_MODE_MOCK) {
        if (key_set(c, "camera.source") && cam->source != RIG_SOURCE_SYNTHETIC)
            return fail_key(c, CFG_ERR_CHECK, "camera.source",
                            "mock mode never opens a camera: use synthetic (or leave it out)");
        cam->source = RIG_SOURCE_SYNTHETIC;
    }
    if (m == RIG_MODE_REPLAY) {
        if (key_set(c, "camera.source"))
            return fail_key(c, CFG_ERR_CHECK, "camera.source",
                            "replay mode reads its frames from replay.video (or the source "
                            "trial's video): leave camera.source out");
        cam->source = RIG_SOURCE_NONE;
    }
    if (cam->roi == RIG_ROI_RECT && cam->width_px > 0 && cam->height_px > 0 &&
        (cam->roi_x + cam->roi_w > cam->width_px || cam->roi_y + cam->roi_h > cam->height_px))
        return fail_key(c, CFG_ERR_CHECK, "camera.roi",
                        "the box %d,%d,%d,%d does not fit in the %d x %d frame", cam->roi_x,
                        cam->roi_y, cam->roi_w, cam->roi_h, cam->width_px, cam->height_px);

    /* Replay sources. */
    if (m == RIG_MODE_REPLAY) {
        rig_replay *rp = &cfg->replay;
        if (!rp->source_trial) {
            if (!rp->video[0])
                return fail_missing(c, "replay", "replay.video",
                                    "replay mode without source_trial: the recorded video");
            if (!cfg->camera.calibration[0])
                return fail_missing(c, "camera", "camera.calibration",
                                    "replay mode without source_trial: the recording camera's "
                                    "calibration file");
            if (!rp->rails[0])
                return fail_missing(c, "replay", "replay.rails",
                                    "replay mode without source_trial: the recorded rail "
                                    "positions, CSV t_s,compress_mm,shear_mm");
        }
    }

    /* API. */
    rig_api *api = &cfg->api;
    if (!is_address(api->listen))
        return fail_key(c, CFG_ERR_VALUE, "api.listen",
                        "'%s' is not an IPv4 or IPv6 address or localhost", api->listen);
    api->loopback = is_loopback(api->listen);
    if (!api->loopback && !api->token[0]) {
        int k = cfg_keys_find_dotted(&key_table, "api.listen");
        char why[160];
        snprintf(why, sizeof why,
                 "api.listen = %s (%s %d) is not a loopback address: a token of at least %d "
                 "characters",
                 api->listen, c->from[k].override ? "--set" : "line",
                 c->from[k].override ? c->from[k].override : c->from[k].line, RIG_TOKEN_MIN_LEN);
        return fail_missing(c, "api", "api.token", why);
    }

    /* Detection. */
    if (cfg->detect.torque_witness && m != RIG_MODE_REPLAY) {
        const char *drv = cfg->has_rails ? cfg->shear.driver : "none";
        if (!cfg->has_rails || (strcmp(drv, "modbus") != 0 && strcmp(drv, "mock") != 0))
            return fail_key(c, CFG_ERR_CHECK, "detect.torque_witness",
                            "only a Modbus shear drive with a load register (or a mock rail, which "
                            "reports the twin's shear force) can report torque or following error; "
                            "the shear rail's driver is %s%s",
                            drv, strcmp(drv, "gcode") == 0 ? " (GRBL reports no torque)" : "");
        if (strcmp(drv, "modbus") == 0 && cfg->shear.modbus.map.load.addr < 0)
            return fail_key(c, CFG_ERR_CHECK, "detect.torque_witness",
                            "the Modbus shear rail's map (%s) names no load register: set "
                            "rail.shear.reg_load (and load_scale) to the drive's torque or "
                            "following-error register",
                            cfg->shear.modbus.map.name);
    }

    /* Prediction resolution. */
    cfg->sim.explicit_resolution = cfg->sim.nodes > 0 || cfg->sim.dt > 0.0;
    return CFG_OK;
}

/* The specimen's own measurements: crease positions in order, folded_at a date-time not in the
 * future (read against this computer's clock at load). Whether the measured creases can be
 * clamped is the prediction's check (daemon/trial/trial_specimen.c), where they meet the scene. */
static cfg_status check_specimen(load_ctx *c)
{
    rig_specimen *sp = &c->cfg.specimen;
    if (isfinite(sp->crease_position_left) && isfinite(sp->crease_position_right) &&
        !(sp->crease_position_left < sp->crease_position_right))
        return fail_key(c, CFG_ERR_CHECK, "specimen.crease_position_right",
                        "the creases cross: crease_position_right = %g is not beyond crease_position_left = %g",
                        sp->crease_position_right, sp->crease_position_left);
    sp->folded_at_s = NAN;
    if (!sp->folded_at[0]) return CFG_OK;
    char why[160];
    double t = NAN;
    if (cfg_datetime_parse(sp->folded_at, &t, why, sizeof why) != CFG_DATETIME_OK)
        return fail_key(c, CFG_ERR_VALUE, "specimen.folded_at", "'%s' is not an ISO 8601 date-time: %s",
                        sp->folded_at, why);
    double now = (double)time(NULL);
    if (t > now + 60.0) /* a minute's grace for clocks set by hand */
        return fail_key(c, CFG_ERR_CHECK, "specimen.folded_at",
                        "'%s' lies in the future (%.3g h after this computer's clock): the creases' age "
                        "would be negative", sp->folded_at, (t - now) / 3600.0);
    sp->folded_at_s = t;
    return CFG_OK;
}

/* Checks that involve the scene: specimen record, gap, soft limits, speeds. */
static cfg_status check_scene(load_ctx *c)
{
    rig_config *cfg = &c->cfg;
    const rod_scene *s = &cfg->scene;
    const double l_mm = 1000.0 * s->length;

    if (!cfg->specimen.name[0]) {
        const char *base = strrchr(cfg->scene_path, '/');
        base = base ? base + 1 : cfg->scene_path;
        size_t n = strcspn(base, ".");
        if (n >= sizeof cfg->specimen.name) n = sizeof cfg->specimen.name - 1;
        memcpy(cfg->specimen.name, base, n);
        cfg->specimen.name[n] = '\0';
    }
    /* The orientation against each crease's own angle (its per-crease key, else folds.angle_deg). */
    rig_crease o = cfg->specimen.crease_orientation;
    for (int k = 0; k < 2 && o != RIG_CREASE_UNSET; k++) {
        double a = rod_scene_crease_angle_deg(s, k), own = k == 0 ? s->fold_angle_left_deg : s->fold_angle_right_deg;
        const char *key = isnan(own) ? "folds.angle_deg" : k == 0 ? "folds.angle_left_deg" : "folds.angle_right_deg";
        if (a != 0.0 && (o == RIG_CREASE_UP) != (a > 0.0))
            return fail_key(c, CFG_ERR_CHECK, "specimen.crease_orientation",
                            "%s does not match the scene's %s = %g (%s is %s)", o == RIG_CREASE_UP ? "up" : "down",
                            key, a, a > 0 ? "a positive angle" : "a negative angle", a > 0 ? "up" : "down");
    }

    cfg_status fst = check_specimen(c);
    if (fst) return fst;

    rig_trial *t = &cfg->trial;
    t->shear_speed_mm_s = 1000.0 * s->shear_rate;
    t->compress_target_mm = rig_calib_compress_mm(&cfg->calib, s->length, s->compression);
    t->shear_end_mm = rig_calib_shear_mm(&cfg->calib, s->length, s->shear_max);
    if (!cfg->has_rails) return CFG_OK;

    /* The gap model follows from the calibration; a rail section that states it must agree. */
    rail_params *cp = &cfg->compress.params;
    double gap0, gap_per;
    rig_calib_gap_model(&cfg->calib, s->length, &gap0, &gap_per);
    origin o0 = rail_origin(c, 0, "gap_at_zero_mm"), o1 = rail_origin(c, 0, "gap_per_mm");
    if ((o0.line || o0.override) && fabs(cp->gap_at_zero_mm - gap0) > 1e-6 * fmax(1.0, fabs(gap0)))
        return fail_rail(c, CFG_ERR_CHECK, 0, "gap_at_zero_mm",
                         "%g disagrees with the calibration: 1000 l + compress_sign * "
                         "compress_zero_mm = %.10g mm (leave it out: it is derived)",
                         cp->gap_at_zero_mm, gap0);
    if ((o1.line || o1.override) && cp->gap_per_mm != gap_per)
        return fail_rail(c, CFG_ERR_CHECK, 0, "gap_per_mm",
                         "%g disagrees with calibration.compress_sign = %+d (gap_per_mm = "
                         "-compress_sign; leave it out: it is derived)",
                         cp->gap_per_mm, cfg->calib.compress_sign);
    cp->gap_at_zero_mm = gap0;
    cp->gap_per_mm = gap_per;
    double rail_floor = cp->min_gap_mm;
    if (cfg->specimen.min_clamp_gap_mm > cp->min_gap_mm) cp->min_gap_mm = cfg->specimen.min_clamp_gap_mm;

    if (cfg->mode == RIG_MODE_REPLAY) return CFG_OK; /* replay moves nothing */

    /* The protocol must be reachable without crossing the gap or the soft limits. */
    double gap_t = l_mm * (1.0 - s->compression);
    if (gap_t < cfg->specimen.min_clamp_gap_mm)
        return fail_key(c, CFG_ERR_CHECK, "specimen.min_clamp_gap_mm",
                        "the scene's compression Delta L = %g (protocol.compression) needs a clamp "
                        "gap of %.6g mm, closer than the specimen's minimum of %g mm",
                        s->compression, gap_t, cfg->specimen.min_clamp_gap_mm);
    if (gap_t < rail_floor)
        return fail_rail(c, CFG_ERR_CHECK, 0, "min_gap_mm",
                         "the scene's compression Delta L = %g (protocol.compression) needs a "
                         "clamp gap of %.6g mm, closer than the rail's minimum of %g mm",
                         s->compression, gap_t, rail_floor);
    /* The compression zero is measured, never driven to (folded ribbons cannot reach it): only
       the target must lie inside the limits. The shear runs from Delta W = 0 to shear_max. */
    const rail_params *cp2 = &cfg->compress.params, *sp = &cfg->shear.params;
    double x = t->compress_target_mm;
    if (x < cp2->soft_min_mm || x > cp2->soft_max_mm)
        return fail_rail(c, CFG_ERR_CHECK, 0, x < cp2->soft_min_mm ? "soft_min_mm" : "soft_max_mm",
                         "the compression target Delta L = %g (protocol.compression) is at rail "
                         "position %.6g mm, outside the soft limits [%g, %g] mm",
                         s->compression, x, cp2->soft_min_mm, cp2->soft_max_mm);
    double y0 = cfg->calib.shear_zero_mm, y1 = t->shear_end_mm;
    if (fmin(y0, y1) < sp->soft_min_mm || fmax(y0, y1) > sp->soft_max_mm)
        return fail_rail(c, CFG_ERR_CHECK, 1,
                         fmin(y0, y1) < sp->soft_min_mm ? "soft_min_mm" : "soft_max_mm",
                         "the shear from Delta W = 0 to %g (protocol.shear_max) runs from rail "
                         "position %.6g to %.6g mm, outside the soft limits [%g, %g] mm",
                         s->shear_max, y0, y1, sp->soft_min_mm, sp->soft_max_mm);

    /* Speeds. */
    if (t->compress_speed_mm_s > cfg->compress.params.max_speed_mm_s)
        return fail_key(c, CFG_ERR_CHECK, "trial.compress_speed_mm_s",
                        "%g mm/s is above rail.compress.max_speed_mm_s = %g", t->compress_speed_mm_s,
                        cfg->compress.params.max_speed_mm_s);
    double vmax = fmin(cfg->compress.params.max_speed_mm_s, cfg->shear.params.max_speed_mm_s);
    if (t->return_speed_mm_s > vmax)
        return fail_key(c, CFG_ERR_CHECK, "trial.return_speed_mm_s",
                        "%g mm/s is above the slower rail's max_speed_mm_s = %g",
                        t->return_speed_mm_s, vmax);
    if (t->shear_speed_mm_s > cfg->shear.params.max_speed_mm_s)
        return fail_rail(c, CFG_ERR_CHECK, 1, "max_speed_mm_s",
                         "%g mm/s is below the scene's protocol.shear_rate = %g m/s (%g mm/s)",
                         cfg->shear.params.max_speed_mm_s, s->shear_rate, t->shear_speed_mm_s);

    /* Mock rails: the soft limits and the start inside the simulated travel. */
    for (int r = 0; r < 2; r++) {
        const rail_config *rc = r == 0 ? &cfg->compress : &cfg->shear;
        if (strcmp(rc->driver, "mock") != 0) continue;
        if (rc->params.soft_min_mm < 0.0)
            return fail_rail(c, CFG_ERR_CHECK, r, "soft_min_mm",
                             "%g mm is outside the mock rail's travel [0, travel_mm = %g]",
                             rc->params.soft_min_mm, rc->mock.travel_mm);
        if (rc->params.soft_max_mm > rc->mock.travel_mm)
            return fail_rail(c, CFG_ERR_CHECK, r, "soft_max_mm",
                             "%g mm is outside the mock rail's travel [0, travel_mm = %g]",
                             rc->params.soft_max_mm, rc->mock.travel_mm);
        if (rc->mock.start_mm > rc->mock.travel_mm)
            return fail_rail(c, CFG_ERR_CHECK, r, "start_mm",
                             "%g mm is outside the mock rail's travel [0, travel_mm = %g]",
                             rc->mock.start_mm, rc->mock.travel_mm);
    }
    return CFG_OK;
}

/* ---- entry points ---------------------------------------------------------------------------- */

static void config_defaults(rig_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->mode = RIG_MODE_RIG;
    cfg->clock = RIG_CLOCK_REAL;
    cfg->outputs = RIG_BASE_FILE;
    cfg->trial.hold_s = 2.0;
    cfg->trial.compress_speed_mm_s = 2.0;
    cfg->trial.return_speed_mm_s = 5.0;
    cfg->trial.min_free_disk_mb = 1000.0;
    cfg->trial.upper_dz_min = 0.05;
    cfg->trial.post_snap_s = 2.0;
    cfg->calib.compress_sign = 1;
    cfg->calib.shear_sign = 1;
    cfg->calib.camera_side = RIG_CAMERA_FRONT;
    cfg->specimen.crease_angle_left_deg = NAN;
    cfg->specimen.crease_angle_right_deg = NAN;
    cfg->specimen.crease_position_left = NAN;
    cfg->specimen.crease_position_right = NAN;
    cfg->specimen.folded_at_s = NAN;
    cfg->camera.fps = 30.0;
    cfg->camera.roi = RIG_ROI_AUTO;
    cfg->camera.margin_px = 20;
    cfg->camera.transcode = RIG_TRANSCODE_FFV1;
    cfg->camera.time_offset_window_s = 4.0;
    cfg->camera.transcode_keep = RIG_KEEP_RECORDED;
    cfg->camera.transcode_threads = 2;
    snprintf(cfg->camera.video_dir, sizeof cfg->camera.video_dir, "videos");
    cfg->camera.noise_sigma = 2.0;
    cfg->camera.blur_sigma_px = 0.8;
    cfg->camera.offset_x_px = -1;
    cfg->camera.offset_y_px = -1;
    cfg->camera.gain_db = -1.0;
    cfg->camera.v4l2_gain = -1.0;
    cfg->camera.ring_frames = 64;
    cfg->camera.track_max_lag = 16;
    cfg->camera.frozen_frames = 12;     /* daemon/trial/trial_capture.h TRIAL_FROZEN_FRAMES */
    cfg->camera.frozen_move_mm = 0.05;  /* ... TRIAL_FROZEN_MOVE_MM */
    cfg->detect.dz_jump = 0.02;
    cfg->detect.min_quality = 0.3;
    cfg->detect.load_jump = 0.5;
    cfg->sim.target_error = 0.01;
    cfg->sim.fast = true;
    cfg->sim.fit = true;
    cfg->sim.fit_refresh_s = 0.5;
    cfg->sim.fit_shape = true;
    cfg->sim.specimen_fit = true;
    static const int ladder[] = {39, 75, 147, 291};
    for (int i = 0; i < 4; i++) cfg->sim.ladder_nodes[i] = ladder[i];
    cfg->sim.n_ladder = 4;
    snprintf(cfg->api.listen, sizeof cfg->api.listen, "127.0.0.1");
    cfg->api.port = 8377;
}

static cfg_status load_all(load_ctx *c, const char *dir, const char *text, size_t len,
                           int n_overrides)
{
    static const cfg_ini_handler h = {.section = on_section, .key = on_key};
    cfg_status st = cfg_ini_parse(c->name, text, len, &h, c, c->err);
    if (st) return st;
    c->lines = cfg_ini_count_lines(text, len);
    for (int i = 0; i < n_overrides; i++)
        if ((st = override_apply(c, i))) return st;
    if (!c->from[0].line) return fail_missing(c, "rig", "rig.mode", "rig | mock | replay");
    if ((st = check_required(c))) return st;
    if ((st = resolve_paths(c, dir))) return st;

    /* The scene: its own errors, unchanged. */
    st = cfg_scene_load(c->cfg.scene_path, c->scene_ovr, c->n_scene_ovr, &c->cfg.scene, c->err);
    if (st) return st;
    if ((st = twin_build(c))) return st;
    if ((st = rails_build(c))) return st;
    if ((st = check_mode(c))) return st;
    if ((st = check_scene(c))) return st;
    if (c->cfg.has_rails) {
        char why[300], key[48];
        for (int r = 0; r < 2; r++) {
            if (rail_config_check(r == 0 ? &c->cfg.compress : &c->cfg.shear, why, sizeof why, key,
                                  sizeof key) != 0)
                return fail_rail(c, CFG_ERR_CHECK, r, key[0] ? key : "driver", "%s", why);
        }
    }
    return CFG_OK;
}

cfg_status rig_config_parse(const char *name, const char *dir, const char *text, size_t len,
                            const char *const *overrides, int n_overrides, rig_config *out,
                            cfg_error *err)
{
    cfg_error local;
    if (!err) err = &local;
    cfg_error_clear(err);
    if (!name) name = "(rig)";
    if (n_overrides < 0 || (n_overrides > 0 && !overrides))
        return cfg_error_set(err, CFG_ERR_SYNTAX, CFG_ORIGIN_OVERRIDE, "--set", 0, NULL, NULL,
                             "missing override list");
    load_ctx *c = calloc(1, sizeof *c);
    if (!c)
        return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, name, 0, NULL, NULL,
                             "out of memory");
    c->name = name;
    c->overrides = overrides;
    c->err = err;
    config_defaults(&c->cfg);
    cfg_status st = load_all(c, dir, text ? text : "", text ? len : 0, n_overrides);
    if (st == CFG_OK && out) {
        rig_config *cfg = &c->cfg;
        /* The file's own absolute path: the name when it is a path, else unknown. */
        if (strchr(name, '/') || dir) {
            const char *base = strrchr(name, '/');
            base = base ? base + 1 : name;
            if (path_join(cfg->path, sizeof cfg->path, cfg->dir, base) < 0) cfg->path[0] = '\0';
        }
        *out = *cfg;
    }
    free(c);
    return st;
}

cfg_status rig_config_load(const char *path, const char *const *overrides, int n_overrides,
                           rig_config *out, cfg_error *err)
{
    cfg_error local;
    if (!err) err = &local;
    char *text;
    size_t len;
    cfg_status st = cfg_ini_read_file(path, RIG_MAX_FILE_BYTES, &text, &len, err);
    if (st) return st;
    char dir[RIG_PATH_MAX];
    const char *slash = strrchr(path, '/');
    if (!slash) {
        snprintf(dir, sizeof dir, ".");
    } else if ((size_t)(slash - path) >= sizeof dir) {
        free(text);
        return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, path, 0, NULL, NULL,
                             "path too long");
    } else {
        size_t n = slash == path ? 1 : (size_t)(slash - path);
        memcpy(dir, path, n);
        dir[n] = '\0';
    }
    st = rig_config_parse(path, dir, text, len, overrides, n_overrides, out, err);
    free(text);
    return st;
}

/* ---- uses ------------------------------------------------------------------------------------- */

void rig_config_rails_to_norm(const rig_config *c, double compress_mm, double shear_mm, double *dl,
                              double *dw)
{
    if (dl) *dl = rig_calib_dl(&c->calib, c->scene.length, compress_mm);
    if (dw) *dw = rig_calib_dw(&c->calib, c->scene.length, shear_mm);
}

void rig_config_norm_to_rails(const rig_config *c, double dl, double dw, double *compress_mm,
                              double *shear_mm)
{
    if (compress_mm) *compress_mm = rig_calib_compress_mm(&c->calib, c->scene.length, dl);
    if (shear_mm) *shear_mm = rig_calib_shear_mm(&c->calib, c->scene.length, dw);
}

static char *json_finish(json_t *o)
{
    if (!o) return NULL;
    char *s = json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
    json_decref(o);
    return s;
}

/* A number, or null when not finite (never NaN in JSON). */
static json_t *json_num(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

char *rig_calibration_json(const rig_config *c)
{
    return c ? rig_calib_json(&c->calib, c->scene.length) : NULL;
}

char *rig_specimen_json(const rig_config *c)
{
    if (!c) return NULL;
    const rig_specimen *sp = &c->specimen;
    const rod_scene *s = &c->scene;
    json_t *o = json_object();
    if (!o) return NULL;
    int bad = 0;
    bad |= json_object_set_new(o, "name", json_string(sp->name));
    bad |= json_object_set_new(o, "material", sp->material[0] ? json_string(sp->material) : json_null());
    bad |= json_object_set_new(o, "crease_angle_left_deg", json_num(sp->crease_angle_left_deg));
    bad |= json_object_set_new(o, "crease_angle_right_deg", json_num(sp->crease_angle_right_deg));
    bad |= json_object_set_new(o, "crease_position_left", json_num(sp->crease_position_left));
    bad |= json_object_set_new(o, "crease_position_right", json_num(sp->crease_position_right));
    bad |= json_object_set_new(o, "folded_at", sp->folded_at[0] ? json_string(sp->folded_at) : json_null());
    bad |= json_object_set_new(o, "crease_orientation",
                               sp->crease_orientation == RIG_CREASE_UP     ? json_string("up")
                               : sp->crease_orientation == RIG_CREASE_DOWN ? json_string("down")
                                                                           : json_null());
    bad |= json_object_set_new(o, "min_clamp_gap_mm", json_num(sp->min_clamp_gap_mm));
    bad |= json_object_set_new(o, "length_m", json_num(s->length));
    bad |= json_object_set_new(o, "width_m", json_num(s->width));
    bad |= json_object_set_new(o, "thickness_m", json_num(s->thickness));
    bad |= json_object_set_new(o, "youngs_modulus_pa", json_num(s->youngs_modulus));
    bad |= json_object_set_new(o, "density_kg_m3", json_num(s->density));
    bad |= json_object_set_new(o, "fold_angle_deg", json_num(s->fold_angle_deg));
    bad |= json_object_set_new(o, "fold_position", json_num(s->fold_position));
    if (bad) {
        json_decref(o);
        return NULL;
    }
    return json_finish(o);
}
