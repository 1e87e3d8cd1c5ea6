/* rail_config.h: the rail sections of a rig INI file, validated into the drivers' parameter
 * structs. One section per rail, "[rail.compress]" and "[rail.shear]"; other sections belong to
 * other loaders and are ignored here. Keys (units in the names):
 *   driver = mock | gcode | modbus
 *   soft_min_mm, soft_max_mm, max_speed_mm_s, accel_mm_s2, poll_hz,
 *   min_gap_mm, gap_at_zero_mm, gap_per_mm                      (all drivers; rail_params)
 *   port, baud, axis, segment_s, segments_ahead, reply_timeout_s, stall_timeout_s,
 *   min_segment_mm                                                  (gcode)
 *   address, rtu (on | off), parity, slave, timeout_s, watchdog_s,
 *   map (a preset name, or a map file NAME.ini relative to the rig file: modbus_map_file.h),
 *   allow_unverified (on | off),
 *   watchdog_external (on | off), counts_per_mm, speed_per_mm_s, accel_per_mm_s2, word_order,
 *   reg_<name> = ADDR[/WORDS] for target_pos speed accel decel op_type trigger control
 *   actual_pos actual_vel status alarm watchdog ident load (-1 = none), load_scale, op_type_abs,
 *   trigger_value,
 *   ctl_stop ctl_estop ctl_home ctl_reset, st_ready st_moving st_in_pos st_alarm st_homing
 *   st_home_end, ident_value                                     (modbus; map = preset first)
 *   start_mm, travel_mm, home_speed_mm_s, stall_at_mm, comm_loss_after_s, alarm_after_s,
 *   alarm_code                                                    (mock, faults for demos)
 * Switches are on | off, as everywhere in a rig file. The table (rail_config_keys) gives each
 * key's kind, bounds, unit and a doc line. A bad value, an unknown key in a rail section or a
 * missing section is an error naming the file, the line and the key. */
#ifndef RIBBON_CONFIG_RAIL_CONFIG_H
#define RIBBON_CONFIG_RAIL_CONFIG_H

#include <stddef.h>

#include "cfg_error.h"
#include "rail_open.h"

/* Largest rail file read (the rig loader's limit, RIG_MAX_FILE_BYTES). */
#define RAIL_CONFIG_MAX_FILE_BYTES (1u << 20)

/* What a rail key holds. */
typedef enum rail_key_kind {
    RAIL_KEY_DOUBLE,     /* a finite number within [min, max] */
    RAIL_KEY_INT,        /* an integer within [min, max] */
    RAIL_KEY_LONG,       /* an integer within [min, max], decimal or 0x hex (codes, bit masks) */
    RAIL_KEY_SWITCH,     /* on | off */
    RAIL_KEY_TEXT,       /* text shorter than the field */
    RAIL_KEY_LETTER,     /* one character (axis, parity) */
    RAIL_KEY_REGISTER,   /* ADDR[/WORDS], -1 = none, ADDR decimal or 0x hex */
    RAIL_KEY_PRESET,     /* map: a Modbus preset name, replacing every register set before */
    RAIL_KEY_WORD_ORDER  /* high_first | low_first */
} rail_key_kind;

/* One key of a rail section (the same keys in [rail.compress] and [rail.shear]; section is
 * "rail" for both, for cfg_keys). */
typedef struct rail_key {
    const char *section;
    const char *name;
    rail_key_kind kind;
    size_t offset;     /* offsetof(rail_config, field) (unused for PRESET, WORD_ORDER) */
    size_t size;       /* TEXT: buffer size */
    double min, max;   /* DOUBLE / INT / LONG bounds */
    const char *unit;  /* "mm", "s", "1", "-" (not a quantity) */
    const char *doc;   /* one line: which driver reads it, and what it is */
} rail_key;

/* A rail section is a driver spec: which driver, and its parameters (drivers/rail_open.h, which
 * opens it). */
typedef rail_open_spec rail_config;

/* The key table, in file order; *n gets its length. Static, read-only data. */
const rail_key *rail_config_keys(size_t *n);

/* Load section [rail.<rail_name>] of path, read line by line with cfg_ini. Returns CFG_OK, or the
 * status (CFG_ERR_IO, _SYNTAX, _UNKNOWN, _VALUE, _RANGE, _MISSING for no such section, _CHECK)
 * with the reason in why: "FILE:LINE: [rail.NAME] KEY: reason" for a bad key. */
cfg_status rail_config_load(const char *path, const char *rail_name, rail_config *out, char *why,
                            size_t why_len);
/* Same from a string (tests); name is used in messages. */
cfg_status rail_config_load_string(const char *text, const char *name, const char *rail_name,
                                   rail_config *out, char *why, size_t why_len);

/* Building blocks for loaders that read the rail sections themselves (config/rig_config.c, which
 * needs its own line numbers, duplicate detection and --set overrides):
 *   rail_config_init   the defaults (driver mock, each driver's *_default(), params.name = rail_name);
 *   rail_config_set    one key = value; "map" loads a preset (replacing every register set before,
 *                      so apply it first); returns CFG_OK, CFG_ERR_VALUE / CFG_ERR_RANGE for a bad
 *                      value or CFG_ERR_UNKNOWN for an unknown key, with the reason (without the
 *                      key) in why;
 *   rail_config_check  the checks rail_config_load runs at the end (driver name, rail_params_check,
 *                      the Modbus map); returns CFG_OK or CFG_ERR_CHECK with the reason in why and
 *                      the blamed key ("soft_min_mm", "reg_status", "map", ... or "") in key;
 *   rail_config_key_name  the i-th accepted key name (NULL past the end), for documentation tests. */
void rail_config_init(rail_config *out, const char *rail_name);
cfg_status rail_config_set(rail_config *c, const char *key, const char *value, char *why,
                           size_t why_len);
/* The same, reading a map file (map = NAME.ini, modbus_map_file.h) relative to base_dir;
 * rail_config_set (base_dir NULL) only accepts the name, without reading the file. */
cfg_status rail_config_set_in(rail_config *c, const char *key, const char *value, const char *base_dir,
                              char *why, size_t why_len);
cfg_status rail_config_check(const rail_config *c, char *why, size_t why_len, char *key,
                             size_t key_len);
const char *rail_config_key_name(size_t i);

/* Load both rail sections of a rig file and open them (rail_open_pair: two gcode rails naming
 * the same port share one controller link). On failure nothing stays open. */
rail_err rail_config_open_rig(const char *path, rail_clock clock, rail **compress, rail **shear, char *why,
                              size_t why_len);

#endif
