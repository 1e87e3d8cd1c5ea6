/* modbus_map_file.h: a Modbus drive's register map read from its own INI file, so a drive that
 * is not ours is described by data (a rig file's `map = maps/NAME.ini`), not by code. The
 * shipped maps are config/maps/ (one NAME.ini each); docs/rails.md explains the format, in short:
 *
 *   [map]                 name (required), verified = yes | no (required: a map not tried on a
 *                         real drive says so, and the driver then wants allow_unverified),
 *                         source, word_order (high_first | low_first), counts_per_mm,
 *                         speed_per_mm_s, accel_per_mm_s2, watchdog_units_per_s, load_scale,
 *                         op_type_abs, trigger_value, ctl_stop ctl_estop ctl_home ctl_reset,
 *                         st_ready st_moving st_in_pos st_alarm st_homing st_home_end,
 *                         ident_value (numbers decimal, codes and masks also 0x hex)
 *   [reg.ROLE]            one per register the driver uses, ROLE one of target_pos speed accel
 *                         decel op_type trigger control actual_pos actual_vel status alarm
 *                         watchdog ident load: address (0-based, decimal or 0x hex; required),
 *                         type = holding | input (default holding; the driver writes only
 *                         holding registers), width = 16 | 32 (default 16), signed = yes | no
 *                         (default: the role's own reading), meaning (the manual's words)
 *   [info.NAME]           a register only the probe reads: address, type (holding | input |
 *                         coil | discrete), width, signed, meaning, scale (unit per count,
 *                         default 1), unit
 *
 * A role without a section is absent from the drive. A bad file fails with its name, line and
 * key ("maps/x.ini:12: reg.status.type: 'word' is not holding, input, coil or discrete"); a key
 * or section set twice is an error. Nothing here opens a drive. */
#ifndef RIBBON_CONFIG_MODBUS_MAP_FILE_H
#define RIBBON_CONFIG_MODBUS_MAP_FILE_H

#include <stddef.h>

#include "cfg_error.h"
#include "rail_modbus_map.h"

/* Largest map file read. */
#define MODBUS_MAP_FILE_MAX_BYTES (64u * 1024u)

/* Read the map file at path into *out (which it overwrites whole). CFG_OK, or the status with
 * the file, line and "section.key" in *err. */
cfg_status modbus_map_file_load(const char *path, rail_modbus_map *out, cfg_error *err);
/* The same from len bytes of text; name is the file name for messages and out->file. */
cfg_status modbus_map_file_parse(const char *name, const char *text, size_t len, rail_modbus_map *out,
                                 cfg_error *err);

#endif
