/* trial_runner.c: the trial state machine and its acquisition loop (see trial_runner.h). */
#include "trial_runner.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "rail_gcode.h"
#include "rail_pair.h"
#include "trial_latency.h"

/* Rail calls in a live trial go under the poller's lock (the rails are not thread-safe). */
static void rails_lock(trial_runner *tr)
{
    if (tr->poller) trial_rail_poller_lock(tr->poller);
}
static void rails_unlock(trial_runner *tr)
{
    if (tr->poller) trial_rail_poller_unlock(tr->poller);
}
/* 0 when the poller of a live trial has a fault (a frozen daemon's clock jump included: the check
 * is made here too, trial_rail_poller.h), with its reason; 1 otherwise. */
static int poller_ok(trial_runner *tr, char *why, size_t why_len)
{
    if (!tr->poller) return 1;
    rail_status a, b;
    double t;
    return trial_rail_poller_latest(tr->poller, &a, &b, &t, why, why_len) == RAIL_OK;
}
/* A live trial sends a move only while the poller sees no fault, checked with the rails' lock
 * held (trial_rail_poller_lock_for_move): after a freeze this thread may wake before the poller,
 * and a move from stale statuses would carry the trial on by itself. */
static rail_err r_move(trial_runner *tr, rail *r, double target, double speed)
{
    char w[256];
    if (tr->poller) {
        if (trial_rail_poller_lock_for_move(tr->poller, w, sizeof w) != RAIL_OK) return RAIL_E_STATE;
    }
    rail_err e = rail_move_abs(r, target, speed);
    rails_unlock(tr);
    return e;
}
static rail_err r_stop(trial_runner *tr, rail *r)
{
    rails_lock(tr);
    rail_err e = rail_stop(r);
    rails_unlock(tr);
    return e;
}
static void r_estop_pair(trial_runner *tr)
{
    rails_lock(tr);
    rail_pair_estop(tr->compress, tr->shear);
    rails_unlock(tr);
}

void trial_runner_set_calibrate(trial_runner *tr, trial_calibrate *calib) { tr->calib = calib; }

void trial_runner_set_live(trial_runner *tr, trial_capture *capture, trial_rail_poller *poller)
{
    tr->capture = capture;
    tr->poller = poller;
}

static const char *const state_names[TRIAL_STATE_COUNT] = {
    "idle", "compressing", "holding", "checking", "shearing", "snapped", "returning", "done", "aborted",
    "failed",
};

const char *trial_state_name(trial_state s)
{
    return (s >= 0 && s < TRIAL_STATE_COUNT) ? state_names[s] : "unknown";
}

int trial_state_final(trial_state s) { return s == TRIAL_DONE || s == TRIAL_ABORTED || s == TRIAL_FAILED; }

/* Abort protocol: 0 none, 1 reason being written, 2 requested (reason readable). */
void trial_runner_abort(trial_runner *tr, const char *reason)
{
    int expected = 0;
    if (!atomic_compare_exchange_strong(&tr->abort_requested, &expected, 1)) return;
    snprintf(tr->abort_reason, sizeof tr->abort_reason, "%s", reason && *reason ? reason : "abort requested");
    atomic_store(&tr->abort_requested, 2);
}

int trial_runner_init(trial_runner *tr, const trial_plan *plan, rail *compress, rail *shear, trial_camera cam,
                      vis_tracker *tracker, trial_sink sink, char *why, size_t why_len)
{
    memset(tr, 0, sizeof *tr);
    if (!plan || !compress || !shear || !cam.grab || !tracker) {
        snprintf(why, why_len, "trial runner: missing rail, camera or tracker");
        return -1;
    }
    if (plan && plan->torque_witness && !(plan->load_jump > 0.0 && isfinite(plan->load_jump))) {
        snprintf(why, why_len, "trial runner: the load witness needs a positive load_jump (got %g)", plan->load_jump);
        return -1;
    }
    if (!(plan->fps > 0.0) || !(plan->compress_speed_mm_s > 0.0) || !(plan->return_speed_mm_s > 0.0) ||
        !(plan->scene.length > 0.0) || !(plan->scene.shear_rate > 0.0)) {
        snprintf(why, why_len, "trial runner: fps, speeds, length and shear rate must be positive");
        return -1;
    }
    tr->plan = *plan;
    tr->compress = compress;
    tr->shear = shear;
    tr->cam = cam;
    tr->tracker = tracker;
    tr->sink = sink;
    atomic_init(&tr->abort_requested, 0);
    atomic_init(&tr->state, TRIAL_IDLE);
    vis_error ve;
    tr->frame = vis_frame_alloc(16, 16, 1, &ve);
    if (!tr->frame) {
        snprintf(why, why_len, "trial runner: %s", ve.message);
        return -1;
    }
    if (plan->cam_offset_window_s > 0.0 &&
        !(tr->cam_watch = trial_cam_watch_alloc(plan->cam_offset_window_s, plan->fps, plan->cam_offset_measure,
                                                plan->calib.camera_time_offset_s, plan->cam_clamp_px[0],
                                                plan->cam_clamp_px[1]))) {
        snprintf(why, why_len,
                 "trial runner: the camera offset's watch cannot start (window %g s, clamp points (%g, %g) and (%g, "
                 "%g) px: they must be at least 20 px apart)",
                 plan->cam_offset_window_s, plan->cam_clamp_px[0][0], plan->cam_clamp_px[0][1], plan->cam_clamp_px[1][0],
                 plan->cam_clamp_px[1][1]);
        trial_runner_free(tr);
        return -1;
    }
    return 0;
}

void trial_runner_free(trial_runner *tr)
{
    vis_frame_free(tr->frame);
    tr->frame = NULL;
    trial_cam_watch_free(tr->cam_watch);
    tr->cam_watch = NULL;
}

/* The loop's working state. */
#define TRIAL_SHAPE_UV_MAX 2048 /* most traced centreline points taken from the tracker for the fit (sim.fit_shape) */

typedef struct run_ctx {
    trial_runner *tr;
    trial_result *res;
    rail_clock clock;
    double t0;            /* rail clock at the start */
    double t;             /* trial time of this iteration */
    double t_state;       /* trial time the current state began */
    double state_limit;   /* s the current state may last */
    trial_state st;
    double start_compress_mm;
    double target_compress_mm, target_shear_mm;
    double last_reading_c, last_reading_s;
    double check_sum;
    int check_n;
    double t_snap;
    rail_status sc, ss;
    /* The load witness (plan.torque_witness), over the fresh shear readings of this shear. */
    int w_n;              /* readings with a load seen */
    double w_prev, w_prev_dw, w_min, w_max;
    int w_fired;          /* the jump was seen */
    double w_dw;          /* Delta W of the reading before the jump */
    double w_until;       /* rail-clock time (trial time) after which a late witness no longer counts */
    int vision_noted;     /* the camera's snap has been handled */
    double t_poll;        /* rail-clock time of the poll that gave sc, ss */
    double t_det_frame;   /* trial time of the frame in which the camera saw the snap (NaN: none) */
    double t_stop_cmd;    /* trial time the shear stop command returned (NaN: none) */
    int stand_noted;      /* the snap-to-stop latency has been reported */
    double t_arrival;     /* trial time this iteration's frame arrived from the camera (NaN: none) */
    double t_picked;      /* trial time this loop took it from the capture ring (NaN: none) */
    double t_tracked;     /* trial time the tracker was done with it (NaN: not tracked) */
    double cpu_tracked;   /* s of this thread's CPU the tracker took on it (NaN: not tracked) */
    trial_latency lat;    /* where the snap-to-stop time went (trial_latency.h) */
    int w_warned;         /* "no load" warning given */
    /* The camera's quality (rig mode, trial_capture.h). */
    double frz_c, frz_s;  /* rail positions at the first frame of the current run of equal frames */
    uint64_t frz_id;      /* its camera id */
    long loss_total;      /* frames lost or incomplete so far */
    double loss_noted_t;  /* trial time of the last loss event (rate: one a second) */
    long loss_noted;      /* loss_total at it */
    double cam_offset;    /* s added to a frame's time to place it on the rails' clock */
    int comp_track_failed; /* a compression frame's tracker failed (said once) */
    /* The compression frames tracked with the clamp point moved (plan.comp_track_from_dl). */
    double comp_t0;       /* monotonic s when the first of them came (NaN: none yet) */
    double comp_busy_s;   /* monotonic s their trackers took */
    double comp_max_s;    /* the longest one */
    long comp_n, comp_measured, comp_over; /* tracked, measured, over plan.comp_track_budget */
    double comp_dl_lo, comp_dl_hi; /* Delta L of the measured ones */
    /* The last compression frame's centreline (sim.fit_shape), with its moved calibration. */
    double shape_uv[2 * TRIAL_SHAPE_UV_MAX];
    size_t shape_n;
    vis_calib shape_cal;
    /* The latest measured compression or hold frame's centreline, not yet offered to the fit
     * (pixels, with its calibration): offered when the next one comes, mapped only when the fit
     * wants it (trial_calibrate_shape_wanted), and at the hold's end handed in as the last. */
    double pend_uv[2 * TRIAL_SHAPE_UV_MAX];
    size_t pend_n;
    vis_calib pend_cal;
    trial_sample pend_smp;
    int have_pend;
} run_ctx;

static int emit_event(run_ctx *c, const char *kind, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int emit_event(run_ctx *c, const char *kind, const char *fmt, ...)
{
    char msg[320];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (c->tr->sink.event) return c->tr->sink.event(c->tr->sink.user, c->t, kind, msg);
    return 0;
}

static void enter(run_ctx *c, trial_state s, double limit_s, const char *why)
{
    c->st = s;
    c->t_state = c->t;
    c->state_limit = limit_s;
    atomic_store(&c->tr->state, s);
    if (c->tr->sink.state) c->tr->sink.state(c->tr->sink.user, s, c->t, why ? why : "");
}

#define RUNNER_STOP_WAIT_S 10.0 /* rail clock time an aborted trial waits for the rails to stand */

/* After a stop: waits on the rail clock (which a mock rig's virtual clock needs to reach the end
 * of the deceleration) until neither rail is moving or homing, at most RUNNER_STOP_WAIT_S, so the
 * trial ends with the rails standing and the next one finds them idle. 0 = standing. */
static int wait_rails_standing(run_ctx *c)
{
    const double t_end = rail_clock_now(c->clock) + RUNNER_STOP_WAIT_S;
    for (int k = 0; k < 100000; k++) {
        rail_status sc, ss;
        char why[128];
        double tp;
        if (c->tr->poller) {
            if (trial_rail_poller_latest(c->tr->poller, &sc, &ss, &tp, why, sizeof why) != RAIL_OK) return -1;
        } else if (rail_pair_poll(c->tr->compress, c->tr->shear, &sc, &ss, why, sizeof why) != RAIL_OK)
            return -1;
        int moving = sc.state == RAIL_STATE_MOVING || sc.state == RAIL_STATE_HOMING ||
                     ss.state == RAIL_STATE_MOVING || ss.state == RAIL_STATE_HOMING;
        if (!moving) return 0;
        if (rail_clock_now(c->clock) >= t_end) return -1;
        rail_clock_sleep(c->clock, 0.01);
    }
    return -1;
}

/* Ends the trial: stops both rails (estop on failure; an abort waits for them to stand), records
 * the reason. */
static void finish(run_ctx *c, trial_state s, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void finish(run_ctx *c, trial_state s, const char *fmt, ...)
{
    int still_moving = 0;
    if (s == TRIAL_FAILED) {
        /* The fault is recorded when it is known, before the stops (over a dead link each stop
         * waits out its write timeout). */
        char reason[sizeof c->res->reason] = "";
        if (fmt) {
            va_list ap;
            va_start(ap, fmt);
            vsnprintf(reason, sizeof reason, fmt, ap);
            va_end(ap);
        }
        emit_event(c, "fault", "%s", reason);
        r_estop_pair(c->tr);
        snprintf(c->res->reason, sizeof c->res->reason, "%s", reason);
        c->res->final = s;
        enter(c, s, 0.0, c->res->reason);
        return;
    } else if (s == TRIAL_ABORTED) {
        /* A stop that fails (a refused write) or rails still moving after the wait (a drive
         * going on to its target) end in the emergency stop of both, never in "aborted" alone. */
        rail_err ec = r_stop(c->tr, c->tr->compress);
        rail_err es = r_stop(c->tr, c->tr->shear);
        still_moving = wait_rails_standing(c) != 0;
        if (ec != RAIL_OK || es != RAIL_OK || still_moving) {
            r_estop_pair(c->tr);
            still_moving = 1;
        }
    }
    c->res->reason[0] = '\0';
    if (fmt) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(c->res->reason, sizeof c->res->reason, fmt, ap);
        va_end(ap);
    }
    if (still_moving) {
        size_t n = strlen(c->res->reason);
        snprintf(c->res->reason + n, sizeof c->res->reason - n,
                 " (a stop failed or the rails were not standing %.0f s after it: both emergency-stopped)",
                 RUNNER_STOP_WAIT_S);
    }
    c->res->final = s;
    if (s != TRIAL_DONE) emit_event(c, s == TRIAL_FAILED ? "fault" : "info", "%s", c->res->reason);
    enter(c, s, 0.0, c->res->reason);
}

static int rail_idle_at(const rail_status *st, double target)
{
    return st->state == RAIL_STATE_IDLE && fabs(st->position_mm - target) < TRIAL_RAIL_ARRIVED_MM;
}

/* Position of a rail at time t (rail clock) from its latest status. A fresh reading is the
 * position at its t_s; an extrapolated status (rail_status_get) is already the position at the
 * poll time t_poll, so only the rest of the way is added. */
static double position_at(const rail_status *st, double t_poll, double t)
{
    if (st->state != RAIL_STATE_MOVING && st->state != RAIL_STATE_HOMING) return st->position_mm;
    return st->position_mm + st->velocity_mm_s * (t - (st->extrapolated ? t_poll : st->t_s));
}

static int command(run_ctx *c, rail *r, rail_err e, const char *what)
{
    if (e == RAIL_OK) return 0;
    char w[256];
    if (!poller_ok(c->tr, w, sizeof w))
        finish(c, TRIAL_FAILED, "%s not sent: rail fault in %s: %s", what, trial_state_name(c->st), w);
    else
        finish(c, TRIAL_FAILED, "%s refused: %s", what, rail_last_error(r));
    return -1;
}

/* Enters snapped: stop the shear. Returns 1 when the stop was refused (trial failed). */
static int stop_for_snap(run_ctx *c)
{
    c->lat.t_decided = rail_clock_now(c->clock) - c->t0;
    if (command(c, c->tr->shear, r_stop(c->tr, c->tr->shear), "shear stop")) return 1;
    c->t_snap = c->t;
    c->t_stop_cmd = c->lat.t_stop_ret = rail_clock_now(c->clock) - c->t0;
    if (c->tr->poller)
        trial_rail_poller_watch_stop(c->tr->poller,
                                     trial_latency_watch_window_s(c->tr->plan.scene.shear_rate * 1000.0,
                                                                  rail_get_params(c->tr->shear)->accel_mm_s2));
    trial_calibrate_snap(c->tr->calib, c->t,
                         c->tr->det.phase != SNAP_WAITING ? snap_detect_dw(&c->tr->det) : c->w_fired ? c->w_dw : NAN);
    enter(c, TRIAL_SNAPPED, c->tr->plan.post_snap_s + 30.0, NULL);
    return 0;
}

/* One fresh shear reading for the load witness (see trial_runner.h), at trial time t and Delta W
 * dw. Returns 1 when the trial ended (the stop was refused). */
static int witness_add(run_ctx *c, double load, double dw, double t)
{
    const trial_plan *p = &c->tr->plan;
    if (c->st != TRIAL_SHEARING && !(c->st == TRIAL_SNAPPED && t <= c->w_until)) return 0;
    if (c->w_n == 0) {
        c->w_min = c->w_max = c->w_prev = load;
        c->w_prev_dw = dw;
        c->w_n = 1;
        return 0;
    }
    double range = c->w_max - c->w_min, jump = fabs(load - c->w_prev);
    int fire = !c->w_fired && c->w_n >= TRIAL_WITNESS_MIN_READINGS && jump > 0.0 && jump > p->load_jump * range;
    double before = c->w_prev, at_dw = c->w_prev_dw;
    c->w_min = fmin(c->w_min, load);
    c->w_max = fmax(c->w_max, load);
    c->w_prev = load;
    c->w_prev_dw = dw;
    c->w_n++;
    if (!fire) return 0;
    c->w_fired = 1;
    c->w_dw = at_dw;
    if (c->tr->det.phase != SNAP_WAITING) {
        emit_event(c, "info",
                   "snap seen by both witnesses: vision at Delta W = %.5f, load at Delta W = %.5f (shear load %.4g -> "
                   "%.4g, %.2f of its range)",
                   snap_detect_dw(&c->tr->det), at_dw, before, load, range > 0.0 ? jump / range : 0.0);
        return 0;
    }
    emit_event(c, "info",
               "load witness: the shear load jumped %.4g -> %.4g (%.2f of its range %.4g, threshold %.2f) after "
               "Delta W = %.5f; the camera sees no snap yet",
               before, load, range > 0.0 ? jump / range : 0.0, range, p->load_jump, at_dw);
    if (c->st == TRIAL_SHEARING) return stop_for_snap(c);
    return 0;
}

static void note_standing(run_ctx *c);
static void comp_track_note(run_ctx *c);

/* One step of the state machine after this iteration's frame. Returns 1 when the trial ended. */
static void shape_offer_pending(run_ctx *c, int last);

static int step(run_ctx *c, const trial_sample *smp)
{
    trial_runner *tr = c->tr;
    const trial_plan *p = &tr->plan;
    double l = p->scene.length;
    if (c->state_limit > 0.0 && c->t - c->t_state > c->state_limit) {
        finish(c, TRIAL_FAILED, "%s did not end within its time limit of %.0f s", trial_state_name(c->st),
               c->state_limit);
        return 1;
    }
    switch (c->st) {
    case TRIAL_COMPRESSING:
        if (rail_idle_at(&c->sc, c->target_compress_mm)) {
            comp_track_note(c);
            emit_event(c, "info", "compression reached: Delta L = %.4f (rail at %.3f mm)",
                       rig_calib_dl(&p->calib, l, c->sc.position_mm), c->sc.position_mm);
            enter(c, TRIAL_HOLDING, p->hold_s + 30.0, NULL);
        }
        return 0;
    case TRIAL_HOLDING:
        if (c->t - c->t_state >= p->hold_s) {
            c->check_sum = 0.0;
            c->check_n = 0;
            vis_tracker_reset(tr->tracker); /* frames during the moves are not trusted */
            shape_offer_pending(c, 1);            /* the hold's last centreline (sim.fit_shape) */
            trial_calibrate_start(tr->calib, c->t); /* on its worker: the shear does not wait */
            enter(c, TRIAL_CHECKING, 10.0 + 10.0 / p->fps, NULL);
        }
        return 0;
    case TRIAL_CHECKING:
        if (smp->measured) {
            c->check_sum += smp->dz;
            c->check_n++;
        }
        if (c->check_n >= 5) {
            double dz = c->check_sum / c->check_n;
            c->res->upper_dz = dz;
            if (!(dz > p->upper_dz_min)) {
                finish(c, TRIAL_FAILED,
                       "not in the upper state: the camera sees Delta Z = %.4f (needs more than %.4f); check the "
                       "specimen and the calibration",
                       dz, p->upper_dz_min);
                return 1;
            }
            emit_event(c, "info", "upper state seen: Delta Z = %.4f", dz);
            c->target_shear_mm = rig_calib_shear_mm(&p->calib, l, p->scene.shear_max);
            double v = p->scene.shear_rate * 1000.0;
            snap_detect_init(&tr->det, &p->snap);
            if (tr->cam_watch) trial_cam_watch_shear(tr->cam_watch, rail_clock_now(c->clock));
            if (command(c, tr->shear, r_move(tr, tr->shear, c->target_shear_mm, v), "shear move")) return 1;
            trial_calibrate_shear_started(tr->calib, c->t);
            enter(c, TRIAL_SHEARING, p->scene.shear_max / (p->scene.shear_rate / l) * 1.5 + 30.0, NULL);
        }
        return 0;
    case TRIAL_SHEARING:
        if (p->torque_witness && !c->w_warned && c->t - c->t_state > 2.0 / rail_get_params(tr->shear)->poll_hz &&
            !c->ss.has_load) {
            c->w_warned = 1;
            emit_event(c, "warning", "load witness on, but the shear rail (%s) reports no load: the camera is the "
                       "only witness", rail_driver_name(tr->shear));
        }
        if (tr->det.phase != SNAP_WAITING) {
            c->vision_noted = 1;
            c->w_until = c->t + TRIAL_WITNESS_LATE_POLLS / rail_get_params(tr->shear)->poll_hz + 2.0 / p->fps;
            c->t_det_frame = c->lat.t_det = smp->t_s;
            c->lat.det_frame = tr->det.detect_frame;
            c->lat.onset_frame = tr->det.onset_frame;
            c->lat.t_onset = tr->det.t_onset;
            c->lat.t_det_arrival = c->t_arrival;
            c->lat.t_picked = c->t_picked;
            c->lat.t_tracked = c->t_tracked;
            c->lat.cpu_tracked = c->cpu_tracked;
            /* The stop first: the event is a store write, which may wait on the disk. */
            if (stop_for_snap(c)) return 1;
            if (snap_detect_gap_frames(&tr->det) > 0)
                emit_event(c, "info",
                           "snap detected at frame %ld across a gap of %ld untracked frames (the trial loop was "
                           "behind): onset Delta W = %.5f, between %.5f and %.5f (uncertainty %.5f)",
                           tr->det.detect_frame, snap_detect_gap_frames(&tr->det), snap_detect_dw(&tr->det),
                           snap_detect_dw(&tr->det), snap_detect_dw_hi(&tr->det),
                           snap_detect_dw_hi(&tr->det) - snap_detect_dw(&tr->det));
            else
                emit_event(c, "info", "snap detected at frame %ld; onset Delta W = %.5f", tr->det.detect_frame,
                           snap_detect_dw(&tr->det));
            return 0;
        }
        if (rail_idle_at(&c->ss, c->target_shear_mm)) {
            emit_event(c, "info", "shear limit reached, no snap (Delta W = %.4f)", p->scene.shear_max);
            goto start_return;
        }
        return 0;
    case TRIAL_SNAPPED:
        if (!c->vision_noted && tr->det.phase != SNAP_WAITING) {
            /* The load witness stopped the shear; now the camera sees the snap too. */
            c->vision_noted = 1;
            emit_event(c, "info",
                       "snap seen by both witnesses: vision at Delta W = %.5f (frame %ld), load at Delta W = %.5f",
                       snap_detect_dw(&tr->det), tr->det.detect_frame, c->w_dw);
        }
        if (tr->det.phase == SNAP_DONE || c->t - c->t_snap >= p->post_snap_s) goto start_return;
        return 0;
    case TRIAL_RETURNING:
        if (rail_idle_at(&c->sc, c->start_compress_mm) && rail_idle_at(&c->ss, p->calib.shear_zero_mm)) {
            finish(c, TRIAL_DONE, NULL);
            return 1;
        }
        return 0;
    default:
        return 0;
    }
start_return : {
    /* A loop that caught up after the snap may get here while the shear still brakes: the
     * return waits (at most the watch's window) for the watch to read it standing, so the
     * latency is measured and no move goes into a deceleration. */
    if (tr->poller && isfinite(c->t_stop_cmd) && !c->stand_noted) {
        double until = rail_clock_now(c->clock) +
                       trial_latency_watch_window_s(p->scene.shear_rate * 1000.0, rail_get_params(tr->shear)->accel_mm_s2);
        while (!isfinite(trial_rail_poller_stop_seen(tr->poller)) && rail_clock_now(c->clock) < until)
            rail_clock_sleep(c->clock, 0.002);
    }
    note_standing(c);
    if (!c->stand_noted && isfinite(c->t_stop_cmd) && isfinite(c->t_det_frame)) {
        /* The return starts before a fresh shear reading showed the rail standing: the command
         * latency is known, the standing one is not (it would be the end of the return). */
        c->stand_noted = 1;
        c->res->stop_cmd_latency_s = c->t_stop_cmd - c->t_det_frame;
        emit_event(c, "info",
                   "snap-to-stop latency: detection frame -> stop command %.1f ms; the shear rail was not read "
                   "standing before the return (rail poll period %.1f ms)",
                   1e3 * c->res->stop_cmd_latency_s, 1e3 / rail_get_params(tr->shear)->poll_hz);
        char msg[320];
        emit_event(c, "info", "%s", trial_latency_format(&c->lat, msg, sizeof msg));
    }
    double dist = fmax(fabs(c->ss.position_mm - p->calib.shear_zero_mm),
                       fabs(c->sc.position_mm - c->start_compress_mm));
    /* Shear back first in the same command batch; both move at the return speed. */
    if (command(c, tr->shear, r_move(tr, tr->shear, p->calib.shear_zero_mm, p->return_speed_mm_s),
                "return of the shear rail"))
        return 1;
    if (command(c, tr->compress, r_move(tr, tr->compress, c->start_compress_mm, p->return_speed_mm_s),
                "return of the compression rail"))
        return 1;
    enter(c, TRIAL_RETURNING, dist / p->return_speed_mm_s * 2.0 + 30.0, NULL);
    return 0;
}
}

/* The rails' statuses of this iteration: the poller's latest in a live trial, else a poll. */
static rail_err poll_rails(run_ctx *c, char *why, size_t why_len)
{
    if (c->tr->poller) return trial_rail_poller_latest(c->tr->poller, &c->sc, &c->ss, &c->t_poll, why, why_len);
    rail_err e = rail_pair_poll(c->tr->compress, c->tr->shear, &c->sc, &c->ss, why, why_len);
    c->t_poll = rail_clock_now(c->clock);
    return e;
}

/* After a snap stop: the first fresh shear reading that is not moving ends the snap-to-stop
 * latency (measured from the detection frame's own time). */
static void note_standing(run_ctx *c)
{
    if (c->stand_noted || !isfinite(c->t_stop_cmd) || !isfinite(c->t_det_frame)) return;
    /* A live trial's poller watched the stop and kept its first standing reading; this loop may
     * come by long after it (issue 34 F: 380-450 ms behind after the snap under load). */
    double seen = c->tr->poller ? trial_rail_poller_stop_seen(c->tr->poller) : NAN;
    if (!isfinite(seen) &&
        (c->ss.extrapolated || c->ss.state == RAIL_STATE_MOVING || c->ss.state == RAIL_STATE_HOMING))
        return;
    double t_stand = (isfinite(seen) ? seen : c->ss.t_s) - c->t0;
    if (t_stand < c->t_stop_cmd) return;
    c->stand_noted = 1;
    c->res->stop_cmd_latency_s = c->t_stop_cmd - c->t_det_frame;
    c->res->stop_stand_latency_s = t_stand - c->t_det_frame;
    emit_event(c, "info",
               "snap-to-stop latency: detection frame -> stop command %.1f ms, -> shear rail standing %.1f ms "
               "(rail poll period %.1f ms, frame period %.1f ms)",
               1e3 * c->res->stop_cmd_latency_s, 1e3 * c->res->stop_stand_latency_s,
               1e3 / rail_get_params(c->tr->shear)->poll_hz, 1e3 / c->tr->plan.fps);
    c->lat.t_stand = t_stand;
    char msg[320];
    emit_event(c, "info", "%s", trial_latency_format(&c->lat, msg, sizeof msg));
}

/* What each rail's controller is set to, stored with the trial (issue 34): for a GRBL rail its
   whole `$$`, whether the board reset on open, and the driver's warnings; nothing for others. */
static void record_rail_settings(run_ctx *c)
{
    rail *rails[2] = {c->tr->compress, c->tr->shear};
    for (int i = 0; i < 2 && c->tr->sink.event; i++) {
        char d[1600], msg[1700];
        if (rail_gcode_describe(rails[i], d, sizeof d) == 0)
            continue;
        snprintf(msg, sizeof msg, "rail settings: rail %s: %s", rail_get_params(rails[i])->name, d);
        c->tr->sink.event(c->tr->sink.user, c->t, "info", msg);
    }
}

/* The monotonic clock, s: what a compression frame's tracker took (the rail clock may be virtual). */
static double mono_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Whether this compression frame is tracked under plan.comp_track_budget: while the trackers'
 * time so far is within that share of the time since the first compression frame came. A live
 * loop so never spends more than that share of the compression on them, whatever one costs on
 * this machine at this resolution; the first is always tracked. */
static int comp_track_due(run_ctx *c)
{
    const double now = mono_now_s();
    if (!isfinite(c->comp_t0)) c->comp_t0 = now;
    const double budget = c->tr->plan.comp_track_budget;
    return !(budget > 0.0) || c->comp_busy_s <= budget * (now - c->comp_t0);
}

/* At the compression's end: how many of its frames were tracked with the clamp point moved, over
 * which Delta L, what they cost and how many the budget left untracked (one info event). */
static void comp_track_note(run_ctx *c)
{
    const trial_plan *p = &c->tr->plan;
    if (!(p->comp_track_from_dl > 0.0) || !isfinite(c->comp_t0)) return;
    char over[160] = "";
    if (p->comp_track_budget > 0.0)
        snprintf(over, sizeof over, "; %ld left untracked by the budget (%.0f%% of the time)", c->comp_over,
                 100.0 * p->comp_track_budget);
    if (c->comp_measured > 0)
        emit_event(c, "info",
                   "compression frames from Delta L %.4f: %ld tracked with the clamp point moved, %ld measured at "
                   "Delta L %.4f to %.4f%s; tracker %.1f ms a frame on average, %.1f ms at most",
                   p->comp_track_from_dl, c->comp_n, c->comp_measured, c->comp_dl_lo, c->comp_dl_hi, over,
                   c->comp_n ? 1e3 * c->comp_busy_s / (double)c->comp_n : 0.0, 1e3 * c->comp_max_s);
    else
        emit_event(c, "info", "compression frames from Delta L %.4f: %ld tracked with the clamp point moved, none "
                   "measured%s", p->comp_track_from_dl, c->comp_n, over);
}

/* A compression frame at Delta L dl measured with the clamp points where the compression rail puts
 * them (trial_comp_track.h). A tracker that fails there leaves the frame untracked ("clamp not
 * found") and says so once in the events; the trial goes on. Returns nonzero only when the trial
 * must stop (never: kept for the loop's shape). */
static int comp_track_frame(run_ctx *c, double dl, vis_measure *m)
{
    trial_runner *tr = c->tr;
    const trial_plan *p = &tr->plan;
    double l = p->scene.length;
    const double t_start = mono_now_s();
    vis_track_params tp = vis_track_params_default();
    tp.length_mm = 1000.0 * l;
    vis_error ve = {0};
    const int want = trial_calibrate_wants_shape(tr->calib);
    c->shape_n = 0;
    if (trial_comp_track_measure_curve(&tp, &p->comp_calib, p->calib.camera_side, l,
                                       rig_calib_dl(&p->calib, l, c->target_compress_mm), dl, tr->frame, m,
                                       want ? c->shape_uv : NULL, TRIAL_SHAPE_UV_MAX, &c->shape_n, &c->shape_cal,
                                       &ve) != VIS_OK) {
        if (!c->comp_track_failed)
            emit_event(c, "warning", "compression frame at Delta L %.4f not tracked: %s (later failures not noted)",
                       dl, ve.message);
        c->comp_track_failed = 1;
        memset(m, 0, sizeof *m);
        m->reason = VIS_REASON_CLAMP_NOT_FOUND;
    }
    const double took = mono_now_s() - t_start;
    c->comp_busy_s += took;
    c->comp_max_s = fmax(c->comp_max_s, took);
    c->comp_n++;
    return 0;
}

/* A measured compression or hold frame's centreline to the fit (sim.fit_shape): n points uv of the
 * tracker with calibration cal, mapped to the plane relative to the simulator's left clamp point
 * (a back camera's image is mirrored: its right clamp point is the simulator's left, the order
 * reversed); last: the hold's last. */
static void shape_to_fit(run_ctx *c, const vis_calib *cal, const double *uv, size_t n, const trial_sample *smp,
                         int last)
{
    trial_runner *tr = c->tr;
    if (n < 2 || !trial_calibrate_wants_shape(tr->calib)) return;
    double xz[2 * TRIAL_SHAPE_UV_MAX];
    int w = vis_frame_width(tr->frame), h = vis_frame_height(tr->frame);
    double lmm = 1000.0 * tr->plan.scene.length;
    vis_calib_curve_to_plane(cal, w, h, lmm, uv, (int)n, xz);
    if (tr->plan.calib.camera_side == RIG_CAMERA_BACK) {
        double r[2];
        vis_calib_curve_to_plane(cal, w, h, lmm, cal->clamp_right_px, 1, r);
        for (size_t i = 0; i < n / 2; i++)
            for (int k = 0; k < 2; k++) {
                double t = xz[2 * i + k];
                xz[2 * i + k] = xz[2 * (n - 1 - i) + k];
                xz[2 * (n - 1 - i) + k] = t;
            }
        for (size_t i = 0; i < n; i++) {
            xz[2 * i] = r[0] - xz[2 * i];
            xz[2 * i + 1] -= r[1];
        }
    }
    trial_calibrate_add_shape(tr->calib, smp->dl, smp->dw, smp->dz, smp->a, xz, (int)n, last);
}

/* The pending centreline to the fit: mapped and handed in when it is the last (the hold ended) or
 * the fit wants its Delta L; dropped otherwise (never needed: trial_calibrate.h). */
static void shape_offer_pending(run_ctx *c, int last)
{
    if (!c->have_pend) return;
    c->have_pend = 0;
    if (last || trial_calibrate_shape_wanted(c->tr->calib, c->pend_smp.dl))
        shape_to_fit(c, &c->pend_cal, c->pend_uv, c->pend_n, &c->pend_smp, last);
}

/* A measured compression or hold frame's centreline (n points in c->pend_uv, with calibration cal)
 * becomes the pending one, after the one before it was offered. */
static void shape_keep_pending(run_ctx *c, const vis_calib *cal, size_t n, const trial_sample *smp)
{
    if (n < 2) return;
    c->pend_n = n;
    c->pend_cal = *cal;
    c->pend_smp = *smp;
    c->have_pend = 1;
}

/* The camera's offset (trial_cam_watch.h): the hold's last frames and the shear's first go to the
 * fit; the frames' own times, before any offset. */
static void cam_watch_frame(run_ctx *c, double t_frame)
{
    const trial_plan *p = &c->tr->plan;
    if (c->st == TRIAL_HOLDING && c->t - c->t_state >= p->hold_s - TRIAL_CAM_WATCH_STAND_S)
        trial_cam_watch_standing(c->tr->cam_watch);
    if (c->st == TRIAL_HOLDING || c->st == TRIAL_CHECKING || c->st == TRIAL_SHEARING)
        trial_cam_watch_frame(c->tr->cam_watch, t_frame, c->tr->frame);
}

/* Once the shear's window is over (or the shear ended: force): the event, the result's fields,
 * and with camera.time_offset = measure the offset for the frames from here on. */
static void cam_watch_poll(run_ctx *c, int force)
{
    trial_cam_offset_fit fit;
    char msg[600];
    force = force || (c->st != TRIAL_SHEARING && c->st != TRIAL_CHECKING && c->st != TRIAL_HOLDING);
    trial_cam_watch_verdict v =
        trial_cam_watch_poll(c->tr->cam_watch, rail_clock_now(c->clock), force, &fit, msg, sizeof msg);
    if (v == TRIAL_CAM_WATCH_PENDING) return;
    if (v != TRIAL_CAM_WATCH_FAILED) {
        c->res->camera_offset_s = fit.offset_s;
        c->res->camera_offset_sd_s = fit.sd_s;
    }
    if (v == TRIAL_CAM_WATCH_USED) c->cam_offset = fit.offset_s;
    if (c->tr->sink.event)
        c->tr->sink.event(c->tr->sink.user, c->t,
                          v == TRIAL_CAM_WATCH_USED || v == TRIAL_CAM_WATCH_AGREES ? "info" : "warning", msg);
}

void trial_runner_run(trial_runner *tr, trial_result *out)
{
    memset(out, 0, sizeof *out);
    snprintf(out->regime, sizeof out->regime, "no snap");
    const trial_plan *p = &tr->plan;
    double l = p->scene.length;
    run_ctx c;
    memset(&c, 0, sizeof c);
    c.tr = tr;
    c.res = out;
    c.clock = rail_get_clock(tr->compress);
    c.t0 = rail_clock_now(c.clock);
    trial_latency_init(&c.lat, c.t0);
    c.t_arrival = c.t_picked = c.t_tracked = c.cpu_tracked = NAN;
    c.last_reading_c = c.last_reading_s = -1.0;
    snap_detect_init(&tr->det, &p->snap);
    char why[256] = "";

    c.t_det_frame = c.t_stop_cmd = NAN;
    c.comp_t0 = NAN;
    c.comp_dl_lo = INFINITY;
    c.comp_dl_hi = -INFINITY;
    out->stop_cmd_latency_s = out->stop_stand_latency_s = NAN;
    out->camera_offset_s = out->camera_offset_sd_s = NAN;
    c.cam_offset = p->calib.camera_time_offset_s;
    record_rail_settings(&c);
    /* Where the rails are, and the preconditions. */
    if (poll_rails(&c, why, sizeof why) != RAIL_OK) {
        finish(&c, TRIAL_FAILED, "rails not ready: %s", why);
        goto end;
    }
    if (c.sc.state != RAIL_STATE_IDLE || c.ss.state != RAIL_STATE_IDLE) {
        finish(&c, TRIAL_FAILED, "rails not idle (compression %s, shear %s)", rail_state_name(c.sc.state),
               rail_state_name(c.ss.state));
        goto end;
    }
    if (fabs(c.ss.position_mm - p->calib.shear_zero_mm) > 0.5) {
        finish(&c, TRIAL_FAILED, "the shear rail is at %.3f mm, not at its zero %.3f mm: return it first",
               c.ss.position_mm, p->calib.shear_zero_mm);
        goto end;
    }
    c.start_compress_mm = c.sc.position_mm;
    c.target_compress_mm = rig_calib_compress_mm(&p->calib, l, p->scene.compression);
    emit_event(&c, "info", "start: compression rail at %.3f mm (Delta L = %.4f), target %.3f mm (Delta L = %.4f)",
               c.sc.position_mm, rig_calib_dl(&p->calib, l, c.sc.position_mm), c.target_compress_mm,
               p->scene.compression);
    if (r_move(tr, tr->compress, c.target_compress_mm, p->compress_speed_mm_s) != RAIL_OK) {
        finish(&c, TRIAL_FAILED, "compression move refused: %s", rail_last_error(tr->compress));
        goto end;
    }
    enter(&c, TRIAL_COMPRESSING,
          fabs(c.target_compress_mm - c.start_compress_mm) / p->compress_speed_mm_s * 2.0 + 30.0, NULL);

    double frame_dt = 1.0 / p->fps, t_next = c.t0;
    for (long frame = 0;; frame++) {
        if (!p->paced_by_camera && !tr->capture) {
            t_next += frame_dt;
            double now = rail_clock_now(c.clock);
            if (t_next > now) rail_clock_sleep(c.clock, t_next - now);
        }
        if (atomic_load(&tr->abort_requested) == 2) {
            finish(&c, TRIAL_ABORTED, "aborted in %s: %s", trial_state_name(c.st), tr->abort_reason);
            break;
        }
        if (poll_rails(&c, why, sizeof why) != RAIL_OK) {
            finish(&c, TRIAL_FAILED, "rail fault in %s: %s", trial_state_name(c.st), why);
            break;
        }
        double now = rail_clock_now(c.clock), t_poll = tr->poller ? c.t_poll : now;
        c.t = now - c.t0;
        trial_calibrate_tick(tr->calib, c.t, c.st == TRIAL_SHEARING);
        trial_sample smp;
        /* Fresh rail readings (not extrapolations) are stored as they come. */
        for (int k = 0; k < 2; k++) {
            const rail_status *st = k ? &c.ss : &c.sc;
            double *last = k ? &c.last_reading_s : &c.last_reading_c;
            if (st->extrapolated || st->t_s == *last) continue;
            *last = st->t_s;
            memset(&smp, 0, sizeof smp);
            smp.kind = 0;
            smp.frame = -1;
            smp.t_s = st->t_s - c.t0;
            smp.compress_mm = position_at(&c.sc, t_poll, st->t_s);
            smp.shear_mm = position_at(&c.ss, t_poll, st->t_s);
            smp.dl = rig_calib_dl(&p->calib, l, smp.compress_mm);
            smp.dw = rig_calib_dw(&p->calib, l, smp.shear_mm);
            smp.reason = VIS_REASON_NONE;
            out->rail_readings++;
            if (tr->sink.sample && tr->sink.sample(tr->sink.user, &smp, why, sizeof why)) {
                finish(&c, TRIAL_FAILED, "sample not stored: %s", why);
                goto end;
            }
            if (k == 1 && tr->cam_watch) trial_cam_watch_reading(tr->cam_watch, st->t_s, st->position_mm);
            if (k == 1 && p->torque_witness && st->has_load && isfinite(st->load) &&
                witness_add(&c, st->load, smp.dw, smp.t_s))
                goto end;
        }
        note_standing(&c);
        /* The frame of this instant, with the rails where they are at its time. */
        double pos_c = position_at(&c.sc, t_poll, now), pos_s = position_at(&c.ss, t_poll, now);
        double dl = rig_calib_dl(&p->calib, l, pos_c), dw = rig_calib_dw(&p->calib, l, pos_s);
        double t_frame = now;
        vis_error ve = {0};
        trial_frame_info fi;
        memset(&fi, 0, sizeof fi);
        fi.index = frame;
        if (tr->capture) {
            if (trial_capture_next(tr->capture, tr->frame, &fi, why, sizeof why)) {
                /* The wait for the frame may have outlasted a rail fault (a whole rig that died):
                 * the rails' fault is named first, the camera's after it. */
                char rwhy[256];
                if (poll_rails(&c, rwhy, sizeof rwhy) != RAIL_OK)
                    finish(&c, TRIAL_FAILED, "rail fault in %s: %s; and %s", trial_state_name(c.st), rwhy, why);
                else
                    finish(&c, TRIAL_FAILED, "%s", why);
                break;
            }
            t_frame = fi.t_s;
            c.t_arrival = fi.host_t_s - c.t0;
            c.t_picked = rail_clock_now(c.clock) - c.t0;
        } else {
            vis_status vs = tr->cam.grab(tr->cam.ctx, now, dl, dw, tr->frame, &t_frame, &ve);
            if (vs != VIS_OK) {
                finish(&c, TRIAL_FAILED, "camera: %s", ve.message[0] ? ve.message : vis_status_str(vs));
                break;
            }
        }
        double t_rail = t_frame + c.cam_offset;
        pos_c = position_at(&c.sc, t_poll, t_rail);
        pos_s = position_at(&c.ss, t_poll, t_rail);
        if (tr->capture) {
            /* Frames lost or incomplete: counted, and shown in the events (at most one a second). */
            c.loss_total += fi.lost_before + fi.incomplete;
            if (c.loss_total > c.loss_noted && (c.loss_noted == 0 || c.t - c.loss_noted_t >= 1.0)) {
                emit_event(&c, "warning",
                           "camera: %ld frames lost or incomplete so far (%ld since the last note), before frame %ld",
                           c.loss_total, c.loss_total - c.loss_noted, fi.index);
                c.loss_noted = c.loss_total;
                c.loss_noted_t = c.t;
            }
            /* A frozen image: the same pixels (or camera id) frame after frame while the rails move.
             * A still scene without noise repeats legitimately, so only motion makes it a fault. */
            if (fi.same_run <= 1) {
                c.frz_c = pos_c;
                c.frz_s = pos_s;
                c.frz_id = fi.camera_id;
            } else if (fi.same_run >= (p->frozen_frames > 0 ? p->frozen_frames : TRIAL_FROZEN_FRAMES)) {
                double moved = fmax(fabs(pos_c - c.frz_c), fabs(pos_s - c.frz_s));
                if (moved >= (p->frozen_move_mm > 0.0 ? p->frozen_move_mm : TRIAL_FROZEN_MOVE_MM)) {
                    finish(&c, TRIAL_FAILED,
                           "camera: the image is frozen: %ld identical frames (camera ids %llu to %llu) while the "
                           "rails moved %.2f mm",
                           fi.same_run, (unsigned long long)c.frz_id, (unsigned long long)fi.camera_id, moved);
                    break;
                }
            }
        }
        memset(&smp, 0, sizeof smp);
        smp.kind = 1;
        smp.frame = tr->capture ? fi.index : frame;
        smp.t_s = t_rail - c.t0;
        smp.compress_mm = pos_c;
        smp.shear_mm = pos_s;
        smp.dl = rig_calib_dl(&p->calib, l, pos_c);
        smp.dw = rig_calib_dw(&p->calib, l, pos_s);
        if (fi.dropped || fi.skip) {
            /* Stored with its time and positions, not tracked: the pipeline's give-way (trial_capture.h). */
            smp.not_tracked = fi.dropped ? 2 : 1;
            smp.reason = VIS_REASON_UNREADABLE;
            if (fi.dropped)
                out->dropped_frames++;
            else
                out->skipped_frames++;
            out->frames++;
            if (tr->sink.sample && tr->sink.sample(tr->sink.user, &smp, why, sizeof why)) {
                finish(&c, TRIAL_FAILED, "sample not stored: %s", why);
                break;
            }
            if (c.st == TRIAL_SHEARING || c.st == TRIAL_SNAPPED)
                snap_detect_add(&tr->det, smp.frame, smp.t_s, smp.dw, 0.0, 0.0, 0);
            if (step(&c, &smp)) break;
            continue;
        }
        if (tr->cam_watch) cam_watch_frame(&c, t_frame);
        vis_measure m;
        int comp_frame = 0; /* tracked with the clamp point moved */
        if (p->clamp_tol_mm > 0 && fabs(pos_c - c.target_compress_mm) > p->clamp_tol_mm) {
            /* The compress rail is moving (or back at zero): the clamps are not at the calibrated
             * points, and a frame measured against those would be a confident wrong answer. */
            memset(&m, 0, sizeof m);
            m.reason = VIS_REASON_CLAMP_NOT_FOUND;
            if (p->comp_track_from_dl > 0.0 && c.st == TRIAL_COMPRESSING && smp.dl >= p->comp_track_from_dl) {
                if (!comp_track_due(&c)) {
                    smp.not_tracked = 3; /* over the budget: stored untracked */
                    c.comp_over++;
                } else if (comp_track_frame(&c, smp.dl, &m)) {
                    break;
                } else {
                    comp_frame = 1;
                }
            }
        } else {
            double cpu0 = trial_latency_thread_cpu_s();
            if (vis_tracker_process(tr->tracker, tr->frame, smp.dw * l * 1000.0, &m, &ve) != VIS_OK) {
                finish(&c, TRIAL_FAILED, "tracker: %s", ve.message);
                break;
            }
            c.t_tracked = rail_clock_now(c.clock) - c.t0;
            c.cpu_tracked = trial_latency_thread_cpu_s() - cpu0;
        }
        smp.reason = m.reason;
        smp.measured = m.reason == VIS_REASON_NONE && m.quality >= p->min_quality && isfinite(m.dz) &&
                       isfinite(m.a);
        if (smp.measured) {
            smp.dz = m.dz;
            smp.a = rig_calib_a_sign(&p->calib) * m.a;
            out->measured_frames++;
            if (comp_frame) {
                c.comp_measured++;
                c.comp_dl_lo = fmin(c.comp_dl_lo, smp.dl);
                c.comp_dl_hi = fmax(c.comp_dl_hi, smp.dl);
            }
            if (c.st >= TRIAL_COMPRESSING && c.st <= TRIAL_SHEARING)
                trial_calibrate_add(tr->calib, c.st == TRIAL_SHEARING, smp.dl, smp.dw, smp.dz, smp.a);
            if ((c.st == TRIAL_COMPRESSING || c.st == TRIAL_HOLDING) && trial_calibrate_wants_shape(tr->calib)) {
                if (comp_frame) {
                    shape_offer_pending(&c, 0);
                    memcpy(c.pend_uv, c.shape_uv, sizeof(double) * 2 * c.shape_n);
                    shape_keep_pending(&c, &c.shape_cal, c.shape_n, &smp);
                } else if (p->comp_track_from_dl > 0.0) { /* comp_calib is the tracker's calibration */
                    shape_offer_pending(&c, 0);
                    size_t n = vis_tracker_samples(tr->tracker, c.pend_uv, TRIAL_SHAPE_UV_MAX);
                    shape_keep_pending(&c, &p->comp_calib, n > TRIAL_SHAPE_UV_MAX ? TRIAL_SHAPE_UV_MAX : n, &smp);
                }
            }
        }
        smp.quality = isfinite(m.quality) ? m.quality : 0.0;
        out->frames++;
        if (tr->capture) {
            /* Live: the frame is judged (a snap stops the shear) before its sample's store write,
             * which may wait for a batch commit (issue 34 F: 58 ms seen on a detection frame). */
            if (c.st == TRIAL_SHEARING || c.st == TRIAL_SNAPPED)
                snap_detect_add(&tr->det, frame, smp.t_s, smp.dw, smp.dz, smp.a, smp.measured);
            int ended = step(&c, &smp);
            if (tr->sink.sample && tr->sink.sample(tr->sink.user, &smp, why, sizeof why)) {
                if (!ended)
                    finish(&c, TRIAL_FAILED, "sample not stored: %s", why);
                else
                    emit_event(&c, "fault", "sample of frame %ld not stored: %s", smp.frame, why);
                break;
            }
            if (ended) break;
            continue;
        }
        if (tr->sink.sample && tr->sink.sample(tr->sink.user, &smp, why, sizeof why)) {
            finish(&c, TRIAL_FAILED, "sample not stored: %s", why);
            break;
        }
        if (!tr->capture && tr->sink.frame && tr->sink.frame(tr->sink.user, tr->frame, frame, why, sizeof why)) {
            finish(&c, TRIAL_FAILED, "video: %s", why);
            break;
        }
        if (c.st == TRIAL_SHEARING || c.st == TRIAL_SNAPPED)
            snap_detect_add(&tr->det, frame, smp.t_s, smp.dw, smp.dz, smp.a, smp.measured);
        if (step(&c, &smp)) break;
        if (tr->cam_watch) cam_watch_poll(&c, 0);
    }
end:
    if (tr->cam_watch) cam_watch_poll(&c, 1);
    out->duration_s = rail_clock_now(c.clock) - c.t0;
    /* The rails stand (finish stopped them): the fit beside a done trial ends, waited for at most
     * its cap. After a failure or an abort its owner cancels and ends it once the trial's final
     * status is stored (trial_session.c): a running fit's prediction cannot be interrupted, and the
     * store read "running" for a failed trial while it finished (2.4 s of the 2.9 s between a
     * dead rig simulator and the stored failure in test_rig_rails, at load 20). */
    c.t = out->duration_s;
    if (out->final == TRIAL_DONE) trial_calibrate_end(tr->calib, c.t, 0);
    out->vision_snapped = snap_detect_snapped(&tr->det);
    out->load_witnessed = c.w_fired;
    out->load_dw = c.w_fired ? c.w_dw : 0.0;
    out->snapped = out->vision_snapped || c.w_fired;
    out->snap_dw = out->vision_snapped ? snap_detect_dw(&tr->det) : c.w_fired ? c.w_dw : 0.0;
    snap_reading reading;
    snap_detect_read(&tr->det, &reading);
    out->asymmetric = reading.regime == SNAP_REGIME_ASYMMETRIC;
    out->regime_undecided = out->vision_snapped && reading.regime == SNAP_REGIME_UNDECIDED;
    out->peak_abs_a = tr->det.peak_abs_a;
    if (out->vision_snapped) {
        /* How the frames read the regime, with its numbers (docs/trials.md "The measured regime"). */
        char msg[512];
        snap_reading_format(&reading, &tr->det.p, msg, sizeof msg);
        emit_event(&c, reading.regime == SNAP_REGIME_UNDECIDED ? "warning" : "info", "%s", msg);
    }
    /* A snap only the load witness saw has no pathway to classify. */
    snprintf(out->regime, sizeof out->regime, "%s",
             out->vision_snapped || !c.w_fired ? snap_detect_regime(&tr->det) : "unknown");
    if (!trial_state_final(out->final)) out->final = TRIAL_FAILED;
}
