/* rail_config.h: the rail sections of a rig INI file, validated into the drivers' parameter
 * structs. One section per rail, "[rail.compress]" and "[rail.shear]"; other sections belong to
 * other loaders and are ignored here. Keys (units in the names):
 *   driver = mock | gcode | modbus
 *   soft_min_mm, soft_max_mm, max_speed_mm_s, accel_mm_s2, poll_hz,
 *   min_gap_mm, gap_at_zero_mm, gap_per_mm                      (all drivers; rail_params)
 *   port, baud, axis, segment_s, segments_ahead, reply_timeout_s, stall_timeout_s,
 *   min_segment_mm                                                  (gcode)
 *   address, rtu, parity, slave, timeout_s, watchdog_s, map, allow_unverified,
 *   watchdog_external, counts_per_mm, speed_per_mm_s, accel_per_mm_s2, word_order,
 *   reg_<name> = ADDR[/WORDS] for target_pos speed accel decel op_type trigger control
 *   actual_pos actual_vel status alarm watchdog ident load (-1 = none), load_scale, op_type_abs,
 *   trigger_value,
 *   ctl_stop ctl_estop ctl_home ctl_reset, st_ready st_moving st_in_pos st_alarm st_homing
 *   st_home_end, ident_value                                     (modbus; map = preset first)
 *   start_mm, travel_mm, home_speed_mm_s, stall_at_mm, comm_loss_after_s, alarm_after_s,
 *   alarm_code                                                    (mock, faults for demos)
 * A bad value, an unknown key in a rail section or a missing section is an error naming the
 * file, the line and the key. */
#ifndef RIBBON_CONFIG_RAIL_CONFIG_H
#define RIBBON_CONFIG_RAIL_CONFIG_H

#include <stddef.h>

#include "rail_open.h"

/* A rail section is a driver spec: which driver, and its parameters (drivers/rail_open.h, which
 * opens it). */
typedef rail_open_spec rail_config;

/* Load section [rail.<rail_name>] of path. Returns 0, or -1 with the reason in why. */
int rail_config_load(const char *path, const char *rail_name, rail_config *out, char *why, size_t why_len);
/* Same from a string (tests); name is used in messages. */
int rail_config_load_string(const char *text, const char *name, const char *rail_name, rail_config *out,
                            char *why, size_t why_len);

/* Building blocks for loaders that read the rail sections themselves (config/rig_config.c, which
 * needs its own line numbers, duplicate detection and --set overrides):
 *   rail_config_init   the defaults (driver mock, each driver's *_default(), params.name = rail_name);
 *   rail_config_set    one key = value; "map" loads a preset (replacing every register set before,
 *                      so apply it first); returns 0, -1 for a bad value or -2 for an unknown key,
 *                      with the reason (without the key) in why;
 *   rail_config_check  the checks rail_config_load runs at the end (driver name, rail_params_check,
 *                      the Modbus map); returns 0 or -1 with the reason in why and the blamed key
 *                      ("soft_min_mm", "reg_status", "map", ... or "") in key;
 *   rail_config_key_name  the i-th accepted key name (NULL past the end), for documentation tests. */
void rail_config_init(rail_config *out, const char *rail_name);
int rail_config_set(rail_config *c, const char *key, const char *value, char *why, size_t why_len);
int rail_config_check(const rail_config *c, char *why, size_t why_len, char *key, size_t key_len);
const char *rail_config_key_name(size_t i);

/* Load both rail sections of a rig file and open them (rail_open_pair: two gcode rails naming
 * the same port share one controller link). On failure nothing stays open. */
rail_err rail_config_open_rig(const char *path, rail_clock clock, rail **compress, rail **shear, char *why,
                              size_t why_len);

#endif
