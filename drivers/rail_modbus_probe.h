/* rail_modbus_probe.h: read every register a Modbus map names, once, and say what each reads,
 * so a lab can check a map against the drive's manual before anything moves
 * (`ribbonctl rail --config rig.ini --rail NAME probe`).
 *
 * The probe only reads: no watchdog is armed, no stop is sent, nothing is written; each register
 * is read with its own table's function (holding 3, input 4, coil 1, discrete input 2). A
 * register that does not answer gets its own row with the reason (a Modbus exception such as
 * "Illegal data address" is the usual sign of a wrong address or type); the others are still
 * read. An unverified map may be probed: that is how it gets verified. */
#ifndef RIBBON_DRIVERS_RAIL_MODBUS_PROBE_H
#define RIBBON_DRIVERS_RAIL_MODBUS_PROBE_H

#include <stdbool.h>
#include <stddef.h>

#include "rail_modbus.h"

#define RAIL_MB_PROBE_MAX (RAIL_MB_ROLES + RAIL_MB_INFO_MAX)

/* One register's reading. */
typedef struct rail_mb_probe_row {
    char name[40];        /* role (target_pos, status, ...) or "info.NAME" */
    rail_mb_reg reg;      /* where, which table, width, sign, meaning */
    bool ok;              /* read; else error says why */
    bool is_signed;       /* how raw was read */
    long raw;             /* the register's value as read (two words joined in the map's order) */
    double value;         /* raw in unit (NAN when the register has no unit: bits, codes) */
    char unit[16];        /* "mm", "mm/s", "mm/s^2", "s", the info register's unit, or "" */
    char text[120];       /* decoded: status bits by name, alarm, identity check; or "" */
    char error[160];
} rail_mb_probe_row;

/* The rows a map would give, without reading (reg, name, unit, is_signed filled; ok false), in
 * the order the probe reads them: roles in rail_modbus_role order, then information registers.
 * Returns the count. */
int rail_modbus_probe_rows(const rail_modbus_map *m, rail_mb_probe_row *rows, int max);
/* Fill value and text of a row from raw (pure; the probe and its tests use it). */
void rail_modbus_probe_decode(const rail_modbus_map *m, rail_mb_probe_row *row, long raw);

/* Connect to the drive (mp->address), read each row once, close. Returns RAIL_OK when every
 * register answered; RAIL_E_DEVICE / _PROTOCOL / _TIMEOUT when some did not (the rows say which);
 * RAIL_E_IO / _INVALID when the drive could not be reached or the map is malformed (why says). */
rail_err rail_modbus_probe(const rail_modbus_params *mp, rail_mb_probe_row *rows, int max, int *n,
                           char *why, size_t why_len);

#endif
