/* rail_modbus.h: rails on Modbus drives (libmodbus, RTU or TCP), driven through a register map.
 *
 * The map says where the drive keeps its target position, speed, acceleration, start trigger,
 * control word (stop, home, alarm reset), actual position and velocity, status bits, alarm
 * code, communication watchdog and identity, how wide each value is (16 or 32 bits) and in which
 * word order 32-bit values travel. Maps come from config or from presets (rail_modbus_map.c):
 * "ribbon-sim" (the simulated drive of ribbon-mbsim, verified by the tests) and "oriental-az"
 * (Oriental Motor AZ series, from its published manual, NOT verified on hardware: needs
 * allow_unverified). Opening a drive probes it read-only first (identity, status, position);
 * nothing is written unless the probe answers sensibly. A dead process cannot leave the rail
 * running: the map's watchdog register is programmed at open (the drive stops and alarms when
 * polls cease), or, for a map without one, the user must state that the drive's own
 * communication timeout is configured (watchdog_external). Opening never re-sends a motion and
 * stops one found in progress. Jogs are bounded moves to the limit in their direction.
 * A map may name a load register (reg_load: torque or following error, signed, 16 or 32 bits,
 * a holding register read with function 3 like the rest): every status then carries its value
 * times load_scale in rail_status.load, the trial runner's second snap witness. */
#ifndef RIBBON_DRIVERS_RAIL_MODBUS_H
#define RIBBON_DRIVERS_RAIL_MODBUS_H

#include <stdbool.h>
#include <stdint.h>

#include "rail.h"

typedef enum rail_mb_word_order {
    RAIL_MB_HIGH_FIRST = 0,  /* 32-bit value: high word at the lower address (most drives) */
    RAIL_MB_LOW_FIRST = 1
} rail_mb_word_order;

/* One value in holding registers: addr < 0 means the drive has no such register. */
typedef struct rail_mb_reg {
    int addr;   /* register address (0-based, as on the wire) */
    int words;  /* 1 (16-bit) or 2 (32-bit, signed) */
} rail_mb_reg;

typedef struct rail_modbus_map {
    char name[32];
    bool verified;                 /* tried on the real drive */
    char source[200];              /* where the map comes from (document, section) */
    rail_mb_word_order word_order;
    double counts_per_mm;          /* position counts per mm (0: must be set in config) */
    double speed_per_mm_s;         /* drive speed units per mm/s (0: = counts_per_mm) */
    double accel_per_mm_s2;        /* drive acceleration units per mm/s^2 (0: = counts_per_mm) */
    rail_mb_reg target_pos, speed, accel, decel, op_type, trigger, control;
    rail_mb_reg actual_pos, actual_vel, status, alarm, watchdog, ident;
    rail_mb_reg load;              /* optional (addr -1 = none): a signed load reading, torque or
                                      following error, read with every status (rail_status.load) */
    double load_scale;             /* rail_status.load per register count (e.g. 0.1 for a torque
                                      register in 0.1 % units); finite and non-zero */
    long op_type_abs;              /* value of op_type meaning "absolute positioning" */
    long trigger_value;            /* written to trigger to start the move */
    long ctl_stop, ctl_estop, ctl_home, ctl_reset; /* control values; 0 = not supported */
    unsigned long st_ready, st_moving, st_in_pos, st_alarm, st_homing, st_home_end; /* bit masks */
    long ident_value;              /* expected identity register value, -1 = any */
    double watchdog_units_per_s;   /* watchdog register units per second (ms: 1000) */
} rail_modbus_map;

/* Fill a preset by name ("ribbon-sim", "oriental-az"); RAIL_E_INVALID for an unknown name. */
rail_err rail_modbus_preset(const char *name, rail_modbus_map *out);
/* Cross-field checks of a map; names the field. */
rail_err rail_modbus_map_check(const rail_modbus_map *m, char *why, size_t why_len);

typedef struct rail_modbus_params {
    char address[160];        /* TCP "HOST:PORT"; RTU: device path or usb:VID:PID[:SERIAL] */
    bool rtu;                 /* RTU on a serial line instead of TCP */
    int baud;                 /* baud (RTU) */
    char parity;              /* 'N', 'E' or 'O' (RTU) */
    int slave;                /* unit / slave id, 1..247 */
    double timeout_s;         /* s, response timeout per request */
    double watchdog_s;        /* s, communication watchdog programmed into the drive */
    bool allow_unverified;    /* explicit opt-in for a preset not tried on hardware */
    bool watchdog_external;   /* the drive's own comm timeout is configured (map without one) */
    rail_modbus_map map;
} rail_modbus_params;

/* Defaults: TCP 127.0.0.1:1502, slave 1, the ribbon-sim map, 0.2 s timeout, 1 s watchdog. */
rail_modbus_params rail_modbus_params_default(void);
rail_err rail_modbus_open(rail **out, const rail_params *p, const rail_modbus_params *m,
                          rail_clock clock, char *why, size_t why_len);

/* State from the status word, the alarm code and whether a homing run was commanded (pure;
 * used by the driver and the fuzz target). msg gets the alarm or fault text, "" otherwise. */
rail_state rail_mb_state_of(const rail_modbus_map *m, unsigned long status, long alarm, bool homing,
                            char *msg, size_t n);

/* Word order helpers (also used by the simulator and the fuzz target). */
void rail_mb_put32(uint16_t *w, int32_t v, rail_mb_word_order o);
int32_t rail_mb_get32(const uint16_t *w, rail_mb_word_order o);

#endif
