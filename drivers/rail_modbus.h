/* rail_modbus.h: rails on Modbus drives (libmodbus, RTU or TCP), driven through a register map.
 *
 * The map says where the drive keeps its target position, speed, acceleration, start trigger,
 * control word (stop, home, alarm reset), actual position and velocity, status bits, alarm
 * code, communication watchdog and identity, how wide each value is (16 or 32 bits) and in which
 * word order 32-bit values travel, and in which table each lives: holding registers are read
 * with function 3 and written with 16, input registers read with 4 (rail_modbus_map.h). Maps come
 * from map files (config/maps/, read by the config layer), from config keys or from presets
 * (rail_modbus_map.c): "ribbon-sim" (the simulated drive of ribbon-mbsim, verified by the tests) and "oriental-az"
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
#include "rail_modbus_map.h"

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

#endif
