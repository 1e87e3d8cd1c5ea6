/* store.h: the SQLite store of ribbon rig: specimens, trials, their samples and events, the
 * simulator's predictions with their curves, and the cached error-against-run-time ladder.
 *
 * One file, WAL journal, a schema versioned by PRAGMA user_version and migrated by code at open
 * (store_schema.c); a file written by a newer program is refused, never touched. Every statement is
 * prepared and bound; no SQL text is ever built from data. Numbers follow one convention at this
 * interface: NaN means "missing" and is stored as SQL NULL (read back as NaN); a NaN where a value
 * is required, or an infinity anywhere, is refused with a reason and nothing is written.
 *
 * Threads: a store handle belongs to one thread at a time. Give each thread its own handle on
 * the same file (the trial runner writes, the API reads): WAL lets readers run beside the one
 * writer, and busy_timeout makes writers wait for each other instead of failing.
 *
 * Durability: a committed transaction survives the death of the process (kill -9); with
 * synchronous=NORMAL the last transactions before a power cut may be lost, the file never corrupts.
 *
 * Times: monotonic trial times are seconds (t_s, double); wall-clock times are passed in as
 * seconds since the Unix epoch (wall_s, from store_wall_now() or a test's fixed value) and stored
 * as ISO-8601 UTC text, "2024-05-01T12:34:56.789Z". The store has no clock of its own except the
 * default creation stamp of a prediction row.
 *
 * Every function that can fail returns a store_err and writes a human reason into why (why_len
 * bytes, may be NULL/0). Records are plain structs; fixed-size text fields are NUL-terminated and
 * truncated on read-back only (the database keeps the full text). */
#ifndef RIBBON_DAEMON_STORE_H
#define RIBBON_DAEMON_STORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <jansson.h>

/* The schema version this program creates and understands (see the migration list in store.c). */
#define STORE_SCHEMA_VERSION 12

/* Errors of the store layer; store_err_message() gives the generic text, why the specific one. */
typedef enum store_err {
    STORE_OK = 0,
    STORE_E_INVALID,    /* bad argument: NaN where required, infinity, unknown name, too long */
    STORE_E_NOTFOUND,   /* no such trial, specimen, prediction or ladder */
    STORE_E_STATE,      /* not allowed in the record's current state (status transition) */
    STORE_E_VERSION,    /* the file's schema is newer than this program, or a migration failed */
    STORE_E_CORRUPT,    /* not a ribbon rig database, or SQLite reports corruption */
    STORE_E_BUSY,       /* another connection held the lock longer than busy_timeout */
    STORE_E_IO,         /* SQLite or the file system failed (open, read, write, disk full) */
    STORE_E_CONSTRAINT, /* the database refused the row (constraint) */
    STORE_E_NOMEM,      /* allocation failed */
    STORE_E_EXISTS,     /* a name already taken (the table's UNIQUE constraint): why names it */
    STORE_E_COUNT
} store_err;

const char *store_err_message(store_err err);

typedef struct store store;

/* ---- opening ------------------------------------------------------------------------------ */

typedef struct store_open_params {
    int busy_timeout_ms; /* ms a writer waits for another writer's lock; default 5000 */
    bool read_only;      /* open without creating or migrating; refused unless fully migrated */
} store_open_params;

store_open_params store_open_params_default(void);

/* Open (creating if missing) and migrate to STORE_SCHEMA_VERSION. PRAGMAs: journal_mode=WAL,
 * foreign_keys=ON, synchronous=NORMAL, busy_timeout. */
store_err store_open(const char *path, store **out, char *why, size_t why_len);
store_err store_open_ex(const char *path, const store_open_params *p, store **out, char *why,
                        size_t why_len);
void store_close(store *st);

/* The schema version of the open file (== STORE_SCHEMA_VERSION after a successful open). */
int store_schema_version(store *st);
/* The underlying connection, for tests and ad-hoc read-only queries. Do not write through it. */
struct sqlite3 *store_handle(store *st);
/* Seconds since the Unix epoch, UTC (CLOCK_REALTIME), for the wall_s arguments below. */
double store_wall_now(void);
/* Format wall_s as ISO-8601 UTC with milliseconds into out (at least 32 bytes). false if
 * wall_s is not finite or out of range. */
bool store_wall_format(double wall_s, char *out, size_t out_len);

/* ---- names of the enumerated columns ---------------------------------------------------- */

typedef enum store_mode { STORE_MODE_RIG = 0, STORE_MODE_MOCK, STORE_MODE_REPLAY, STORE_MODE_COUNT } store_mode;

typedef enum store_status {
    STORE_STATUS_CREATED = 0, /* recorded, not started (prediction may be running) */
    STORE_STATUS_RUNNING,     /* rails may move */
    STORE_STATUS_DONE,        /* ran to its end (snap or shear limit) */
    STORE_STATUS_FAILED,      /* a fault ended it; reason says which */
    STORE_STATUS_ABORTED,     /* a user or a signal ended it */
    STORE_STATUS_INTERRUPTED, /* the daemon died before it ended (found at start-up) */
    STORE_STATUS_COUNT
} store_status;

typedef enum store_regime {
    STORE_REGIME_UNKNOWN = 0, /* not measured / not predicted: SQL NULL, JSON null */
    STORE_REGIME_SYMMETRIC,   /* "symmetric": saddle-node first */
    STORE_REGIME_ASYMMETRIC,  /* "asymmetric": pitchfork first */
    STORE_REGIME_NO_SNAP,     /* "no snap": shear limit reached without a snap */
    STORE_REGIME_COUNT
} store_regime;

typedef enum store_event_kind {
    STORE_EVENT_STATE = 0, /* the runner entered a state */
    STORE_EVENT_INFO,
    STORE_EVENT_WARNING,
    STORE_EVENT_FAULT,
    STORE_EVENT_COUNT
} store_event_kind;

typedef enum store_sample_kind { STORE_SAMPLE_RAIL = 0, STORE_SAMPLE_FRAME = 1 } store_sample_kind;

/* Names as stored ("rig", "running", "no snap", "warning"); NULL for values out of range
 * (store_regime_name(STORE_REGIME_UNKNOWN) is NULL). The parsers return false on unknown text;
 * store_regime_parse also takes "none" (ribbon-sim's word) for "no snap". */
const char *store_mode_name(store_mode m);
const char *store_status_name(store_status s);
const char *store_regime_name(store_regime r);
const char *store_event_kind_name(store_event_kind k);
bool store_mode_parse(const char *s, store_mode *out);
bool store_status_parse(const char *s, store_status *out);
bool store_regime_parse(const char *s, store_regime *out);
bool store_event_kind_parse(const char *s, store_event_kind *out);

/* ---- specimens (store_specimens.c) --------------------------------------------------------- */

#define STORE_SPECIMEN_CALIBRATION_MAX 4096        /* bytes of calibration_json, with its NUL */
#define STORE_SPECIMEN_CALIBRATION_FAILURE_MAX 1024 /* bytes of calibration_failure_json, with its NUL */

typedef struct store_specimen {
    int64_t id;                    /* set by the store */
    char name[64];                 /* unique, non-empty: the label on the specimen */
    double length_m;               /* m, required > 0 */
    double width_m;                /* m, required > 0 */
    double thickness_m;            /* m, required > 0 */
    double youngs_modulus_pa;      /* Pa, > 0; NaN = unknown */
    double density_kg_m3;          /* kg/m^3, > 0; NaN = unknown */
    char material[32];             /* "PET", ...; "" = unknown */
    double crease_angle_left_deg;  /* deg, measured; NaN = not measured */
    double crease_angle_right_deg; /* deg, measured; NaN = not measured */
    double fold_position;          /* Gamma, fraction of the free length in (0, 0.5]; NaN = unknown */
    char crease_orientation[16];   /* "up", "down", ...; "" = unknown */
    int64_t trials_count;          /* read only: trials the specimen has been through */
    double crease_position_left;   /* measured, fraction of the free length in (0, 1); NaN = not measured */
    double crease_position_right;  /* measured, in (0, 1); NaN = not measured */
    char folded_at[40];            /* when the creases were folded, ISO 8601 as written; "" = unknown */
    double phi_deg;                /* design fold angle (magnitude), deg in (0, 180); NaN = unknown */
    int state;                     /* store_specimen_state; new on insert, then set by the calls below */
    char state_reason[128];        /* why retired or broken; "" = none */
    char state_at[32];             /* when the state last changed, ISO-8601 UTC; "" = never */
    /* Read only (v12), written by store_specimen_set_calibration, never by an upsert: */
    char calibration_json[STORE_SPECIMEN_CALIBRATION_MAX]; /* its strip fitted to its trials (a JSON
                                      object, trial_specimen_calib.h); "" = none yet */
    char calibration_failure_json[STORE_SPECIMEN_CALIBRATION_FAILURE_MAX]; /* the last refit's
                                      failure (a JSON object); "" = none since the last success */
} store_specimen;

/* A specimen's life: new (never trialled), in use (trialled), retired or broken (no more
 * trials: a start naming it is refused). */
typedef enum store_specimen_state {
    STORE_SPECIMEN_NEW = 0,
    STORE_SPECIMEN_IN_USE,
    STORE_SPECIMEN_RETIRED,
    STORE_SPECIMEN_BROKEN,
    STORE_SPECIMEN_STATE_COUNT
} store_specimen_state;
const char *store_specimen_state_name(store_specimen_state s); /* "new", "in use", ...; NULL out of range */
bool store_specimen_state_parse(const char *s, store_specimen_state *out);

store_specimen store_specimen_default(void); /* every optional number NaN, texts empty */

/* Insert, or update every field but trials_count of the specimen with the same name. */
store_err store_specimen_upsert(store *st, const store_specimen *sp, int64_t *id, char *why, size_t why_len);
/* Insert a new specimen only: a name already taken is STORE_E_EXISTS ("specimen NAME exists"),
 * decided by the table's UNIQUE constraint (no look first, so two writers cannot both pass). */
store_err store_specimen_insert(store *st, const store_specimen *sp, int64_t *id, char *why, size_t why_len);
store_err store_specimen_get(store *st, int64_t id, store_specimen *out, char *why, size_t why_len);
store_err store_specimen_get_by_name(store *st, const char *name, store_specimen *out, char *why,
                                     size_t why_len);
/* One more trial for the specimen (call when the rails first touch it); a new specimen becomes
 * in use. */
store_err store_specimen_count_trial(store *st, int64_t id, char *why, size_t why_len);
/* Every specimen, by name. *out malloc'ed (free()); NULL when *n == 0. */
store_err store_specimen_list(store *st, store_specimen **out, size_t *n, char *why, size_t why_len);
/* The specimen's calibration (v12). calibration_json non-NULL: the new calibration (a JSON object
 * shorter than STORE_SPECIMEN_CALIBRATION_MAX), the last failure cleared. NULL: failure_json (a
 * JSON object shorter than STORE_SPECIMEN_CALIBRATION_FAILURE_MAX) is the refit's failure and the
 * calibration before it is kept. Allowed in every state (a retired specimen's last trial ends
 * after the retirement). STORE_E_INVALID naming the field; STORE_E_NOTFOUND. */
store_err store_specimen_set_calibration(store *st, int64_t id, const char *calibration_json,
                                         const char *failure_json, char *why, size_t why_len);
/* Retire (or mark broken) with a reason (required). Retired and broken are final: a second
 * retirement is STORE_E_STATE naming the first. */
store_err store_specimen_retire(store *st, int64_t id, store_specimen_state state, const char *reason,
                                double wall_s, char *why, size_t why_len);

/* ---- the queue (store_queue.c) -------------------------------------------------------------
 * Items wait 'queued' in order of position (1 .. n, no gaps); one at a time runs; each ends done,
 * failed, aborted, skipped (removed before it ran) or unknown (found running at start-up). The
 * queue's state row says whether it runs and why not. A running item can be neither removed nor
 * moved (STORE_E_STATE). */

typedef enum store_queue_kind {
    STORE_QUEUE_TRIAL = 0, /* "trial": a trial of a specimen with overrides and a note */
    STORE_QUEUE_OPERATOR,  /* "operator": a step the lab does; holds the queue until confirmed */
    STORE_QUEUE_PAUSE,     /* "pause": stops the queue when reached */
    STORE_QUEUE_KIND_COUNT
} store_queue_kind;

typedef enum store_queue_status {
    STORE_QUEUE_QUEUED = 0, STORE_QUEUE_RUNNING, STORE_QUEUE_DONE, STORE_QUEUE_FAILED, STORE_QUEUE_ABORTED,
    STORE_QUEUE_SKIPPED, STORE_QUEUE_UNKNOWN, STORE_QUEUE_STATUS_COUNT
} store_queue_status;

#define STORE_QUEUE_JSON_MAX 4096 /* bytes of an item's set_json, fields_json, values_json */

typedef struct store_queue_item {
    int64_t id;
    store_queue_kind kind;
    store_queue_status status;
    int64_t position;        /* 1 .. n while queued; 0 otherwise */
    int64_t specimen_id;     /* 0 = none (required for a trial) */
    char specimen_name[64];  /* read only */
    char set_json[STORE_QUEUE_JSON_MAX];    /* a trial's overrides: JSON array of "section.key=value" */
    char note[256];
    char prompt[256];        /* an operator step's text */
    char fields_json[STORE_QUEUE_JSON_MAX]; /* an operator step's fields: JSON array of names */
    char values_json[STORE_QUEUE_JSON_MAX]; /* the values it was confirmed with (JSON object); "" = none */
    int64_t trial_id;        /* a trial item's trial once started; 0 = none */
    char reason[512];        /* why it ended as it did; "" = none */
    char created_at[32], started_at[32], ended_at[32];
} store_queue_item;

const char *store_queue_kind_name(store_queue_kind k);
bool store_queue_kind_parse(const char *s, store_queue_kind *out);
const char *store_queue_status_name(store_queue_status s);

/* A zeroed item with set_json "[]" and fields_json "[]". */
store_queue_item store_queue_item_default(void);
/* Appends a queued item (kind, specimen_id, set_json, note, prompt, fields_json are read). */
store_err store_queue_add(store *st, const store_queue_item *it, double wall_s, int64_t *id, char *why,
                          size_t why_len);
store_err store_queue_get(store *st, int64_t id, store_queue_item *out, char *why, size_t why_len);
/* Every item: the running one, the queued ones by position, then the history newest first.
 * *out malloc'ed (free()); NULL when *n == 0. */
store_err store_queue_list(store *st, store_queue_item **out, size_t *n, char *why, size_t why_len);
/* The first queued item (NOTFOUND when none), the running one (NOTFOUND when none). */
store_err store_queue_next(store *st, store_queue_item *out, char *why, size_t why_len);
store_err store_queue_current(store *st, store_queue_item *out, char *why, size_t why_len);
/* A queued item leaves the queue as skipped with the reason. */
store_err store_queue_remove(store *st, int64_t id, const char *reason, double wall_s, char *why, size_t why_len);
/* A queued item to position (1 .. n; larger means last). */
store_err store_queue_move(store *st, int64_t id, int64_t position, char *why, size_t why_len);
/* queued -> running (started now); the item leaves the order. */
store_err store_queue_item_begin(store *st, int64_t id, double wall_s, char *why, size_t why_len);
store_err store_queue_item_set_trial(store *st, int64_t id, int64_t trial_id, char *why, size_t why_len);
/* running -> an end status with a reason; values_json (NULL = keep) is stored with it. */
store_err store_queue_item_end(store *st, int64_t id, store_queue_status status, const char *reason,
                               const char *values_json, double wall_s, char *why, size_t why_len);
/* The same and, when stop_reason is not NULL, the queue stopped with it: one transaction, so a
 * crash or a failed write leaves either both (the item ended, the queue stopped) or neither (the
 * item still running, to be ended again), never an ended item with the queue running on. */
store_err store_queue_item_end_stop(store *st, int64_t id, store_queue_status status, const char *reason,
                                    const char *values_json, const char *stop_reason, double wall_s, char *why,
                                    size_t why_len);
/* The queue's state: running or not, and why (reason_len bytes), changed_at (32 bytes, may be NULL). */
store_err store_queue_state_get(store *st, bool *running, char *reason, size_t reason_len, char *changed_at,
                                char *why, size_t why_len);
store_err store_queue_state_set(store *st, bool running, const char *reason, double wall_s, char *why,
                                size_t why_len);
/* At daemon start-up, one transaction: every running item becomes unknown, and the queue is
 * stopped, saying why (the items found running, or that the daemon restarted) if it ran. *count
 * gets how many items became unknown. A restart never resumes the queue. */
store_err store_queue_recover(store *st, double wall_s, int *count, char *why, size_t why_len);

/* ---- the planner's proposals (store_plans.c) ----------------------------------------------- */

typedef enum store_plan_status {
    STORE_PLAN_PROPOSED = 0, /* "proposed": may be approved */
    STORE_PLAN_APPROVED,     /* "approved": its specimen and queue items exist (final) */
    STORE_PLAN_SUPERSEDED,   /* "superseded": a newer plan replaced it (final) */
    STORE_PLAN_STATUS_COUNT
} store_plan_status;
const char *store_plan_status_name(store_plan_status s);

typedef struct store_plan_proposal {
    int64_t id;              /* set by the store */
    int64_t batch;           /* set by the store: one per store_plan_add_batch call */
    double phi_deg, gamma;   /* the specimen to make: design angle (deg) and position */
    double sd_before;        /* the belief's sd of Gamma* at that phi when proposed */
    double predicted_gamma;  /* the model's Gamma* there (before the offset) */
    double offset_mean, offset_sd; /* the fitted systematic offset (0, 0 without calibration) */
    int calibrated;          /* 1: offset fitted; 0: fixed at 0 */
    store_plan_status status;
    int64_t specimen_id, operator_item_id, trial_item_id; /* 0 until approved */
    char specimen_name[64];  /* read only */
    char created_at[32], approved_at[32];
} store_plan_proposal;

/* A new plan: every still 'proposed' proposal becomes 'superseded', then the n proposals are
 * added as one batch (ids back in p[k].id). One transaction. */
store_err store_plan_add_batch(store *st, store_plan_proposal *p, size_t n, double wall_s, char *why, size_t why_len);
store_err store_plan_get(store *st, int64_t id, store_plan_proposal *out, char *why, size_t why_len);
/* Every proposal, newest first. *out malloc'ed (free()); NULL when *n == 0. */
store_err store_plan_list(store *st, store_plan_proposal **out, size_t *n, char *why, size_t why_len);
/* Marks a 'proposed' proposal approved with its specimen and queue items: STORE_E_STATE naming
 * its status otherwise, STORE_E_NOTFOUND. */
store_err store_plan_approve(store *st, int64_t id, int64_t specimen_id, int64_t operator_item_id,
                             int64_t trial_item_id, double wall_s, char *why, size_t why_len);
/* What an approval made. */
typedef struct store_plan_approval {
    int64_t specimen_id, operator_item_id, trial_item_id;
} store_plan_approval;
/* The whole approval of proposal id in one transaction: the new specimen sp
 * (store_specimen_insert: a name taken is STORE_E_EXISTS), the operator step op and the trial
 * item trial appended to the queue for it (their specimen_id is the new specimen's), and the
 * proposal marked approved with the three (STORE_E_STATE when it is not 'proposed',
 * STORE_E_NOTFOUND). All of it or nothing: any failure rolls every row back. */
store_err store_plan_approve_new(store *st, int64_t id, const store_specimen *sp, const store_queue_item *op,
                                 const store_queue_item *trial, double wall_s, store_plan_approval *out,
                                 char *why, size_t why_len);

/* ---- trials (store_trials.c) ------------------------------------------------------------ */

/* What a new trial is created from. */
typedef struct store_trial_def {
    store_mode mode;
    const char *config_text;      /* the whole rig file, then the scene text; required ("" allowed) */
    const char *calibration_json; /* JSON text of the calibration record; NULL = none; must parse */
    int64_t specimen_id;          /* 0 = none */
    int64_t source_trial_id;      /* 0 = none; a replay's recorded trial */
    const char *video_path;       /* NULL = none yet */
    const char *software_version; /* NULL = this program's RIBBON_VERSION */
    double created_wall_s;        /* s since the Unix epoch, required */
    double crease_age_s;          /* s from the specimen's folding to the trial, >= 0; NaN = unknown */
} store_trial_def;

store_trial_def store_trial_def_default(void); /* mock, config "", created now */

typedef struct store_trial {
    int64_t id;
    store_mode mode;
    store_status status;
    char state[32];             /* last runner state, "" = none */
    char reason[512];           /* why it failed / aborted / stopped, "" = none */
    int64_t specimen_id;        /* 0 = none */
    char specimen_name[64];     /* "" = none */
    int64_t source_trial_id;    /* 0 = none */
    char video_path[512];       /* "" = none */
    char created_at[32];        /* ISO-8601 UTC */
    char started_at[32];        /* "" = not started */
    char ended_at[32];          /* "" = not ended */
    int snapped;                /* -1 = not measured, 0 = no snap, 1 = snapped */
    double snap_dw_measured;    /* Delta W = dw / l at the snap; NaN = none */
    store_regime regime_measured;
    char software_version[32];
    int64_t samples;            /* samples stored for the trial */
    double stop_cmd_latency_s;  /* s, snap detection frame -> shear stop command returned; NaN = none */
    double stop_stand_latency_s; /* s, snap detection frame -> shear rail read standing; NaN = none */
    double crease_age_s;        /* s from the specimen's folding to the trial; NaN = unknown */
    int64_t video_bytes;        /* size of video_path when it was recorded or transcoded; -1 = unknown */
} store_trial;

store_err store_trial_create(store *st, const store_trial_def *def, int64_t *id, char *why, size_t why_len);
/* Status transitions: created -> running -> done | failed | aborted | interrupted, and
 * created -> failed | aborted. The end states are final (STORE_E_STATE). running stamps
 * started_at, an end state ended_at, both with wall_s. reason NULL or "" keeps the current one. */
store_err store_trial_set_status(store *st, int64_t id, store_status status, const char *reason, double wall_s,
                                 char *why, size_t why_len);
/* The runner's current state name ("compressing", "shearing", ...; < 32 bytes). */
store_err store_trial_set_state(store *st, int64_t id, const char *state, char *why, size_t why_len);
/* The measured result. snapped: snap_dw finite, regime symmetric or asymmetric, or unknown (SQL
 * NULL: a snap only the shear drive's load witnessed, the camera saw no pathway).
 * Not snapped: snap_dw NaN, regime no-snap. */
store_err store_trial_set_result(store *st, int64_t id, bool snapped, double snap_dw, store_regime regime,
                                 char *why, size_t why_len);
/* The snap-to-stop latency (s; NaN = not measured, stored NULL; negative or infinite refused). */
store_err store_trial_set_latency(store *st, int64_t id, double stop_cmd_s, double stop_stand_s, char *why,
                                  size_t why_len);
store_err store_trial_set_video(store *st, int64_t id, const char *video_path, char *why, size_t why_len);
/* The camera's time offset measured at the shear's start (s, finite) and its standard deviation
 * (s, finite, >= 0); STORE_E_INVALID otherwise, the row untouched. */
store_err store_trial_set_camera_offset(store *st, int64_t id, double offset_s, double sd_s, char *why,
                                        size_t why_len);
/* The calibrated prediction beside the scene's (issue 32 B, store_calibrated.c): snap_dw (NaN: no
 * snap), its 1-sigma band snap_sd and p_other (NaN: no band), regime ("symmetric", "asymmetric",
 * "no snap"), fit_json (a JSON object: the fitted parameters with their standard errors), failure
 * NULL. Or, failure non-NULL, the named reason the fit failed (the other fields cleared). A later
 * call replaces an earlier one. Non-finite numbers other than NaN are refused. */
typedef struct store_calibrated {
    double snap_dw, snap_sd, p_other;
    const char *regime;
    const char *fit_json;
    const char *failure;
} store_calibrated;
store_err store_trial_set_calibrated(store *st, int64_t id, const store_calibrated *c, char *why, size_t why_len);
/* The trial's video file and its size in bytes (>= 0): the raw recording at the trial's end, then
 * the transcoded file once it is verified (trial_transcoder.h). roi (NULL: unchanged): the new
 * file's region x, y, w, h inside the full frame, written into the calibration record's "roi" in
 * the same statement (a transcode that kept only part of the recorded region). */
store_err store_trial_set_video_file(store *st, int64_t id, const char *video_path, int64_t bytes, const int roi[4],
                                     char *why, size_t why_len);
/* At daemon start-up: every unfinished trial ('running', or 'created': killed before it started
 * moving) becomes 'interrupted' (ended at wall_s, a reason and a fault event added). *count gets
 * how many. One transaction. */
store_err store_trial_mark_interrupted(store *st, double wall_s, int *count, char *why, size_t why_len);

store_err store_trial_get(store *st, int64_t id, store_trial *out, char *why, size_t why_len);
/* Every trial, oldest first. *out is malloc'ed (free()); NULL when *n == 0. */
store_err store_trial_list(store *st, store_trial **out, size_t *n, char *why, size_t why_len);
/* The long texts of a trial, malloc'ed (free()); *calibration_json NULL when none.
 * Either pointer may be NULL if not wanted. */
store_err store_trial_texts(store *st, int64_t id, char **config_text, char **calibration_json, char *why,
                            size_t why_len);

/* ---- events (store_events.c) ------------------------------------------------------------ */

typedef struct store_event {
    int64_t id;            /* set by the store */
    int64_t trial_id;
    double t_s;            /* s on the trial's monotonic clock; NaN = before the clock started */
    double wall_s;         /* s since the Unix epoch, required on append; NaN on read-back */
    char wall_time[32];    /* read back: ISO-8601 UTC */
    char state[32];        /* runner state when it happened; "" = none */
    store_event_kind kind;
    char message[512];     /* required, non-empty */
} store_event;

store_err store_event_append(store *st, const store_event *ev, char *why, size_t why_len);
/* A trial's events in order. *out malloc'ed (free()). */
store_err store_events_get(store *st, int64_t trial_id, store_event **out, size_t *n, char *why, size_t why_len);
/* Trial times (s) at which a stored trial entered the checking, shearing and returning states,
 * from its state events ("state NAME..."); NaN for a state it never entered (or unreadable events). */
void store_events_state_times(store *st, int64_t trial_id, double *t_check, double *t_shear, double *t_return);

/* ---- samples (store_samples.c) ---------------------------------------------------------- */

typedef struct store_sample {
    int64_t seq;            /* set by the writer: 0, 1, 2, ... per trial */
    double t_s;             /* s on the trial's monotonic clock, required */
    store_sample_kind kind; /* rail reading or camera frame */
    int64_t frame;          /* camera frame index, -1 = none */
    double compress_mm;     /* mm, compression rail position; NaN = missing */
    double shear_mm;        /* mm, shear rail position; NaN = missing */
    double dl, dw, dz, a;   /* Delta L, Delta W, Delta Z (/ l) and asymmetry A; NaN = missing */
    double quality;         /* tracker quality in [0, 1]; NaN = missing */
    char reason[96];        /* why a value is missing ("ribbon lost"); "" = none */
} store_sample;

store_sample store_sample_default(void); /* rail kind, frame -1, every value NaN */

/* The batched writer. Samples collect in memory and go out in one transaction when the batch
 * holds batch_rows rows, when a sample's t_s is max_age_s past the last commit, on flush and on
 * end. The caller's t_s is the only clock. */
typedef struct store_writer_params {
    size_t batch_rows; /* rows per transaction; default 256 */
    double max_age_s;  /* s between commits at most, on the samples' clock; default 0.25 */
} store_writer_params;

store_writer_params store_writer_params_default(void);

typedef struct store_samples store_samples;

/* p NULL = defaults. Numbering continues after the trial's last stored sample. A writer uses
 * its store's connection: end it before store_close, and keep both on one thread. */
store_err store_samples_begin(store *st, int64_t trial_id, const store_writer_params *p, store_samples **out,
                              char *why, size_t why_len);
/* Copy one sample into the batch (committing if due). STORE_E_INVALID: the sample was refused
 * (NaN t_s, infinity, bad kind or frame, quality outside [0,1]) and not added. Any other error
 * is a failed commit: the sample was added and every row stays pending for the next commit;
 * once the batch is full, add refuses (not added) until a flush succeeds. */
store_err store_samples_add(store_samples *w, const store_sample *s, char *why, size_t why_len);
store_err store_samples_flush(store_samples *w, char *why, size_t why_len);
/* Flush and free (freed even when the flush fails; the error says how many rows were lost). */
store_err store_samples_end(store_samples *w, char *why, size_t why_len);
int64_t store_samples_committed(const store_samples *w); /* rows committed by this writer */
size_t store_samples_pending(const store_samples *w);    /* rows waiting for a commit */

store_err store_samples_count(store *st, int64_t trial_id, int64_t *count, char *why, size_t why_len);
/* A trial's samples in seq order. *out malloc'ed (free()). */
store_err store_samples_get(store *st, int64_t trial_id, store_sample **out, size_t *n, char *why,
                            size_t why_len);

/* ---- curves for reports (store_curve.c, store_samples.c, store_predictions.c) ------------------------------ */

/* A curve as parallel arrays. Curves the store returns live in one block: free with
 * store_curve_free(). Curves a caller passes in are only read. */
typedef struct store_curve {
    size_t n;
    double *t_s; /* s */
    double *dw;  /* Delta W */
    double *dz;  /* Delta Z; NaN = missing (predictions only) */
    double *a;   /* A; NaN = missing (predictions only) */
} store_curve;

void store_curve_free(store_curve *c);
/* The measured curve: camera frames with dw, dz and a all present, in time order. */
store_err store_trial_curve(store *st, int64_t trial_id, store_curve *out, char *why, size_t why_len);

/* ---- predictions (store_predictions.c) and the ladder (store_ladder.c) ----------------------------------------- */

/* Where a value a prediction used came from. */
typedef enum store_source {
    STORE_SOURCE_UNKNOWN = 0, /* not recorded (rows from before schema 5): SQL NULL, JSON null */
    STORE_SOURCE_SCENE,       /* "scene": the scene file (with its --set overrides) */
    STORE_SOURCE_SPECIMEN,    /* "specimen": the rig file's [specimen] measurement */
    STORE_SOURCE_COUNT
} store_source;

const char *store_source_name(store_source s); /* "scene", "specimen"; NULL for unknown */
bool store_source_parse(const char *s, store_source *out);

/* The creases a prediction used, [0] the left one (near the clamp at x = 0), [1] the right one:
 * each crease's own angle in deg signed as the scene's folds.angle_deg (before the imperfection
 * seed, which is the prediction's imperfection), positions from the left clamp point as fractions
 * of the free length. NaN with STORE_SOURCE_UNKNOWN = not recorded. The hinge is the scene's
 * folds.hinge_stiffness: the crease model the prediction ran. */
typedef struct store_creases {
    double angle_deg[2];
    store_source angle_from[2];
    double position[2];
    store_source position_from[2];
    double hinge_stiffness; /* N m/rad, > 0; INFINITY = rigid creases; NaN = not recorded (before v7) */
} store_creases;

store_creases store_creases_unknown(void); /* every value NaN, every source unknown */

typedef enum store_prediction_status {
    STORE_PREDICTION_DONE = 0, /* "done": it ran (snapped or not) */
    STORE_PREDICTION_FAILED    /* "failed": no prediction; failure says why (the trial ran anyway) */
} store_prediction_status;

typedef struct store_prediction {
    int64_t id;                 /* set by the store */
    store_prediction_status status;
    char failure[512];          /* FAILED: the reason, required; DONE: "" */
    int64_t trial_id;           /* 0 = not tied to a trial */
    char scene_hash[72];        /* required, non-empty: hash of the scene text it was made for */
    bool snapped;
    double snap_dw;             /* Delta W at the snap; required finite when snapped, NaN otherwise */
    store_regime regime;        /* symmetric / asymmetric when snapped, no snap otherwise */
    double peak_abs_a;          /* peak |A| during the snap; NaN = unknown */
    int nodes;                  /* rod nodes, required > 1 */
    double dt;                  /* s, (initial) time step, required > 0 */
    bool adaptive;              /* adaptive time stepping */
    double imperfection;        /* fold_angle_rel of the scene, required finite */
    double est_error;           /* estimated |error| of snap_dw from the ladder; NaN = unknown */
    double wall_s;              /* s of run time, required >= 0 */
    char software_version[32];  /* "" = this program's RIBBON_VERSION */
    char *solver_json;          /* solver settings, JSON text; NULL = none; must parse */
    store_curve curve;          /* t_s and dw required, dz and a may be NaN */
    char created_at[32];        /* read back: ISO-8601 UTC */
    store_creases creases;      /* the creases as measured (specimen) or designed (scene), and where
                                   each came from; calibration_json says which values replaced them */
    char *calibration_json;     /* the specimen's calibration it ran with (a JSON object, v12): the
                                   values it took, each with the one it replaced; NULL = none */
} store_prediction;

store_prediction store_prediction_default(void);

/* Insert with its curve, in one transaction. A FAILED prediction has snapped false, snap_dw
 * NaN, regime unknown, no curve and a non-empty failure; nodes, dt and wall_s are those it was
 * attempted at (wall_s: what it cost before it failed). */
store_err store_prediction_insert(store *st, const store_prediction *p, int64_t *id, char *why, size_t why_len);
/* Read back (curve, solver_json and calibration_json allocated: release with store_prediction_free). */
store_err store_prediction_get(store *st, int64_t id, store_prediction *out, char *why, size_t why_len);
/* The trial's latest prediction. STORE_E_NOTFOUND when it has none. */
store_err store_prediction_get_by_trial(store *st, int64_t trial_id, store_prediction *out, char *why,
                                        size_t why_len);
void store_prediction_free(store_prediction *p);
/* The predicted curve of a trial's latest prediction (curve only). */
store_err store_prediction_curve(store *st, int64_t trial_id, store_curve *out, char *why, size_t why_len);

/* One rung of the error-against-run-time ladder: a resolution, its snap and what it cost. */
typedef struct store_ladder_rung {
    int nodes;        /* required > 1 */
    double dt;        /* s, required > 0 */
    bool adaptive;
    double snap_dw;   /* NaN = no snap at this resolution */
    double est_error; /* estimated |error| of snap_dw; NaN = unknown */
    double wall_s;    /* s of run time, required >= 0 */
} store_ladder_rung;

/* Replace the ladder of scene_hash by these rungs (one transaction). The hash should cover
 * everything the ladder depends on: scene text, solver settings and software version. */
store_err store_ladder_put(store *st, const char *scene_hash, const store_ladder_rung *rungs, size_t n,
                           char *why, size_t why_len);
/* The ladder, cheapest rung first. STORE_E_NOTFOUND when none is cached. *out malloc'ed. */
store_err store_ladder_get(store *st, const char *scene_hash, store_ladder_rung **out, size_t *n, char *why,
                           size_t why_len);

/* ---- JSON (store_json.c) --------------------------------------------------------------------- */

/* One trial as a JSON object; the keys (a missing value is null, never NaN):
 *   id, mode, status, state, reason, snapped, snap_dw_measured, snap_dw_predicted,
 *   regime_measured, regime_predicted, samples, video_path, source_trial, specimen,
 *   created, started, ended, software_version,
 *   crease_age_s,
 *   snap_dw_calibrated, snap_sd_calibrated (1 sigma), regime_calibrated,
 *   p_other_regime_calibrated, fit_failure, fit (the stored fit_json or null),
 *   prediction: null or {id, status ("done" | "failed"), failure, nodes, dt, adaptive, est_error,
 *                        wall_s, imperfection, scene_hash,
 *                        creases: {angle_left_deg, angle_left_from, angle_right_deg,
 *                                  angle_right_from, position_left, position_left_from,
 *                                  position_right, position_right_from},
 *                        calibration: the specimen's calibration it ran with (v12) or null}
 * store_trial_json adds events: [{t_s, wall_time, state, kind, message}] and calibration
 * (the parsed calibration record or null). *out is a new reference. */
store_err store_trial_json(store *st, int64_t id, json_t **out, char *why, size_t why_len);
/* Every trial (oldest first), without events and calibration. */
store_err store_trials_json(store *st, json_t **out_array, char *why, size_t why_len);

/* ---- CSV export (store_export.c) ------------------------------------------------------------- */

/* One trial's samples: a header line, then one row per sample; a missing value is an empty
 * cell; text is quoted when it needs to be (RFC 4180). Columns:
 *   seq,t_s,kind,frame,compress_mm,shear_mm,dl,dw,dz,a,quality,reason
 * (kind is "rail" or "frame"). Numbers round-trip exactly. */
store_err store_export_trial_csv(store *st, int64_t id, FILE *out, char *why, size_t why_len);
/* The same text in memory (the API's GET /trials/{id}/samples.csv): *text malloc'ed (the caller
 * frees it), *len bytes, NUL-terminated. STORE_E_NOTFOUND for an unknown trial. */
store_err store_export_trial_csv_text(store *st, int64_t id, char **text, size_t *len, char *why, size_t why_len);
/* Into dir (created if missing): trials.csv (one row per trial, the JSON keys flattened) and
 * trial-<id>-samples.csv per trial. Each file is written beside and renamed when complete. */
store_err store_export_all(store *st, const char *dir, char *why, size_t why_len);

/* ---- benchmark (store_bench.c) ---------------------------------------------------------------- */

/* Create a fresh database at path (refused if the file exists), write n_samples through the
 * batched writer with default parameters into one trial, and report samples per second
 * (wall time from begin to the end's last commit). The file is left for inspection. */
store_err store_bench_samples(const char *path, int64_t n_samples, double *samples_per_s, char *why,
                              size_t why_len);

#endif
