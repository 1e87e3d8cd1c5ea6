/* rail_mock.h: a rail with no hardware: rail_axis kinematics on a real or virtual clock, plus
 * fault injection (stall at a position, communication loss and device alarm after a time), and an
 * external load input (rail_mock_set_load).
 * Used by mock mode and by tests of everything above the drivers. */
#ifndef RIBBON_DRIVERS_RAIL_MOCK_H
#define RIBBON_DRIVERS_RAIL_MOCK_H

#include "rail.h"

typedef struct rail_mock_params {
    double start_mm;           /* mm, position at open */
    double travel_mm;          /* mm, hard travel [0, travel] of the simulated rail */
    double home_speed_mm_s;    /* mm/s, speed of the homing run toward 0 */
    double stall_at_mm;        /* mm, NaN = off: the motor stalls when it reaches this position */
    double comm_loss_after_s;  /* s after open, negative = off: the link goes silent */
    double alarm_after_s;      /* s after open, negative = off: the drive raises an alarm */
    int alarm_code;            /* device code reported with the injected alarm */
} rail_mock_params;

rail_mock_params rail_mock_params_default(void);
rail_err rail_mock_open(rail **out, const rail_params *p, const rail_mock_params *m, rail_clock clock,
                        char *why, size_t why_len);

/* The load the mock drive reports from now on (rail_status.has_load, .load), in whatever unit the
 * caller feeds (mock mode: the digital twin's shear force, N), as a drive with a force sensor or a
 * torque monitor would; the value stands until the next call. A mock rail reports no load until
 * the first call. RAIL_E_UNSUPPORTED for a rail of another driver, RAIL_E_INVALID for NaN/Inf. */
rail_err rail_mock_set_load(rail *r, double load);

#endif
