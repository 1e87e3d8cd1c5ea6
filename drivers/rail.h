/* rail.h: the one interface every linear rail driver implements (mock, G-code/GRBL, Modbus).
 *
 * Units at this interface are mm, mm/s and mm/s^2; each driver converts to its device's units
 * (steps, counts, mm/min) at its own edge. A rail is a small vtable (rail_ops) behind a front end
 * (rail.c) that owns everything drivers must not get wrong on their own:
 *   - every motion command is checked against the rail's soft limits, its speed limit and, for the
 *     compression rail, the specimen's minimum clamp gap BEFORE the driver sees it; a refused
 *     command sends nothing and leaves a reason in rail_last_error();
 *   - homing needs an explicit confirmation flag (a clamped specimen would be crushed);
 *   - status polls are rate limited to the rail's configured poll rate, and every status carries
 *     the monotonic time of the device reading it came from (see "Reconstruction" below).
 * Drivers keep a dead process from leaving a rail moving: GRBL moves go out as short jog segments
 * that the front end tops up on every poll (stop polling and the rail stops within a segment);
 * Modbus drives run under the drive's communication watchdog. Opening or reconnecting a rail never
 * resumes a motion that was in progress. Stopping the other rail on a fault is done by
 * rail_pair_poll() (rail_pair.h), through which the trial runner polls both rails.
 * Time comes from a rail_clock (rail_clock.h) so the mock runs on a virtual clock in tests.
 * A rail is not thread-safe: one thread (the trial runner's loop) owns both rails; GRBL rails
 * need rail_status_get() at least every 1 / poll_hz seconds while they move, or they stop.
 *
 * Reconstruction. rail_status_get() reads the device when the last reading is 1 / poll_hz old
 * (or after any command: the first status after a command is always a fresh reading); in between
 * it returns the last reading (p0, v0 at t0, its state, code and message) with position and
 * velocity reconstructed for the time now - t0 and `extrapolated` set. Only a reading whose state
 * is moving or homing is reconstructed; any other reading is returned as it is. The model is the
 * last command the front end sent (a command refused before sending changes nothing), with the
 * acceleration accel_mm_s2 = a:
 *   - move_abs / move_rel to T at speed s, and jog at v (recorded as a move to the end of the
 *     allowed travel in v's direction at |v|): a trapezoidal profile from the reading's measured
 *     velocity v0: ramp at +-a toward sign(T - p0) * s, cruise, brake at a to rest exactly on T
 *     (a triangle when the move is too short to reach s; when v0 is already too fast to stop
 *     before T, braking at a from t0). The position is capped at T: it never passes the target.
 *     This is the law rail_axis (the mock and the simulators) follows, so the two agree up to the
 *     axis's 1 ms integration sub-step;
 *   - stop / estop: braking at a from v0 to rest, so it moves at most v0^2 / (2a) from p0 (the
 *     first status after the stop call is a fresh reading taken after it, so p0 and v0 are
 *     already the device's while braking, and p0 + v0^2/(2a) is where braking from the stop
 *     call ends);
 *   - home, or nothing known (after open or reset, or after the driver failed to send a
 *     command): straight on at the measured velocity, p0 + v0 (now - t0).
 * A fresh reading always replaces the reconstruction: nothing of it is carried over. */
#ifndef RIBBON_DRIVERS_RAIL_H
#define RIBBON_DRIVERS_RAIL_H

#include <stdbool.h>
#include <stddef.h>

#include "rail_clock.h"

/* Errors of the drivers layer. rail_err_message() gives the generic text; rail_last_error() the
 * specific reason of the last failure on one rail (which value, which byte, which register). */
typedef enum rail_err {
    RAIL_OK = 0,
    RAIL_E_INVALID,      /* bad argument or configuration value (NaN, Inf, out of range) */
    RAIL_E_LIMIT,        /* target outside the configured soft limits */
    RAIL_E_SPEED,        /* speed zero, negative or above the configured limit */
    RAIL_E_GAP,          /* the move would bring the clamps closer than the minimum gap */
    RAIL_E_CONFIRM,      /* homing asked for without the explicit confirmation */
    RAIL_E_STATE,        /* not allowed in the current state (alarm, fault, disconnected) */
    RAIL_E_IO,           /* the transport failed to open, read or write */
    RAIL_E_TIMEOUT,      /* the device did not answer in time */
    RAIL_E_PROTOCOL,     /* malformed, truncated or unexpected reply */
    RAIL_E_DEVICE,       /* the device refused the command or reported an alarm */
    RAIL_E_DISCONNECTED, /* the link to the device is lost */
    RAIL_E_UNSUPPORTED,  /* the driver cannot do this */
    RAIL_E_NOMEM,        /* allocation failed */
    RAIL_E_UNVERIFIED,   /* an unverified drive preset was chosen without the explicit opt-in */
    RAIL_E_COUNT
} rail_err;

const char *rail_err_message(rail_err err);

/* s: the longest the monotonic clock may run past a rail's poll period (1 / poll_hz) between two
 * status reports of a moving rail before the process counts as having been frozen (SIGSTOP, a
 * suspended machine): the trial poller's TRIAL_CLOCK_JUMP_S, and the G-code driver's bound before
 * it sends another jog segment. */
#define RAIL_CLOCK_JUMP_S 0.5

/* What the rail is doing, as the device (or the link to it) says. */
typedef enum rail_state {
    RAIL_STATE_IDLE = 0,
    RAIL_STATE_MOVING,
    RAIL_STATE_HOMING,
    RAIL_STATE_ALARM,        /* device alarm: needs a reset (and usually homing) before motion */
    RAIL_STATE_FAULT,        /* driver-detected fault: stall, refused command, bad replies */
    RAIL_STATE_DISCONNECTED, /* no answer from the device */
    RAIL_STATE_COUNT
} rail_state;

const char *rail_state_name(rail_state s);

/* One reading of the rail. */
typedef struct rail_status {
    rail_state state;
    double position_mm;    /* mm, machine position along the rail */
    double velocity_mm_s;  /* mm/s, signed */
    int code;              /* device's own code (GRBL alarm/error number, drive alarm), 0 = none */
    double t_s;            /* s, monotonic time of the device reading this comes from */
    bool extrapolated;     /* true if position and velocity were reconstructed since the
                              reading at t_s (see "Reconstruction" above) */
    bool has_load;         /* the drive reported a load with this reading (a second snap witness) */
    double load;           /* the drive's own load unit, valid when has_load: what the Modbus map's
                              reg_load holds times load_scale (torque in % of rated, or following
                              error in mm, as the map says), or the mock's external load
                              (rail_mock_set_load; mock mode: the twin's shear force in N). GRBL
                              reports none. Extrapolated statuses carry the last reading's load. */
    char message[160];     /* human text for state/code ("" when idle and fine) */
} rail_status;

/* Limits and timing shared by every driver. */
typedef struct rail_params {
    char name[32];          /* "compress", "shear" or anything; appears in every reason */
    double soft_min_mm;     /* mm, lowest position any command may target */
    double soft_max_mm;     /* mm, highest position any command may target */
    double max_speed_mm_s;  /* mm/s, highest speed any command may ask for */
    double accel_mm_s2;     /* mm/s^2, acceleration the drive is configured for (for stop
                               distances and the mock's profile) */
    double poll_hz;         /* Hz, highest rate of device status reads (GRBL docs: about 5 Hz) */
    /* Clamp gap (compression rail only; min_gap_mm = 0 disables the check). The gap between the
       clamps is gap_at_zero_mm + gap_per_mm * position_mm. */
    double min_gap_mm;      /* mm, the specimen's minimum clamp gap */
    double gap_at_zero_mm;  /* mm, clamp gap when this rail is at position 0 */
    double gap_per_mm;      /* mm of gap per mm of rail travel: +1 or -1 */
} rail_params;

rail_params rail_params_default(void);
/* Check one parameter set; names the bad field in why. */
rail_err rail_params_check(const rail_params *p, char *why, size_t why_len);

/* The driver vtable. Positions arriving here are already checked against every limit.
 * impl is the driver's own object. Drivers write a reason with rail_set_error() on failure. */
typedef struct rail rail;
typedef struct rail_ops {
    const char *name;                                          /* "mock", "gcode", "modbus" */
    rail_err (*poll)(rail *r, void *impl, rail_status *out);   /* read the device now */
    rail_err (*move_abs)(rail *r, void *impl, double target_mm, double speed_mm_s);
    /* Constant velocity until stop or until end_mm (the limit in the direction of motion). */
    rail_err (*jog)(rail *r, void *impl, double velocity_mm_s, double end_mm);
    rail_err (*stop)(rail *r, void *impl);   /* decelerating stop */
    rail_err (*estop)(rail *r, void *impl);  /* fastest stop the device has; may need reset */
    rail_err (*home)(rail *r, void *impl);
    rail_err (*reset)(rail *r, void *impl);  /* clear an alarm; never moves */
    void (*close)(void *impl);
} rail_ops;

/* Front end. rail_create takes ownership of impl (closed by ops->close on failure too). */
rail_err rail_create(rail **out, const rail_params *p, rail_clock clock, const rail_ops *ops,
                     void *impl, char *why, size_t why_len);
void rail_close(rail *r);

rail_err rail_status_get(rail *r, rail_status *out);    /* rate limited, may reconstruct */
rail_err rail_status_poll(rail *r, rail_status *out);   /* always reads the device */
rail_err rail_move_abs(rail *r, double target_mm, double speed_mm_s);
rail_err rail_move_rel(rail *r, double delta_mm, double speed_mm_s);
rail_err rail_jog(rail *r, double velocity_mm_s);       /* signed; runs until stop or a limit */
rail_err rail_stop(rail *r);
rail_err rail_estop(rail *r);
rail_err rail_home(rail *r, bool confirmed);            /* confirmed must be true */
rail_err rail_reset(rail *r);
/* Poll (at the poll rate) until the rail is no longer moving or homing, at most timeout_s.
 * Returns RAIL_OK when it ended idle, RAIL_E_STATE/DEVICE/DISCONNECTED otherwise. */
rail_err rail_wait_idle(rail *r, double timeout_s, rail_status *out);

const char *rail_last_error(const rail *r);
const rail_params *rail_get_params(const rail *r);
const char *rail_driver_name(const rail *r);
rail_clock rail_get_clock(const rail *r);
/* Stop distance from speed v at the configured acceleration: v^2 / (2 a), mm. */
double rail_stop_distance_mm(const rail *r, double v_mm_s);

/* For drivers: record the reason of a failure (printf style); returns err. */
rail_err rail_set_error(rail *r, rail_err err, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* For drivers' own extensions (rail_mock_set_load): the driver object of r when r runs on ops,
 * NULL when it is another driver's rail. */
void *rail_driver_impl(rail *r, const rail_ops *ops);

/* Copy src into dst (n bytes), truncating, always terminated. */
void rail_text_copy(char *dst, size_t n, const char *src);

#endif
