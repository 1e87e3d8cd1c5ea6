/* rail_open.h: the driver factory. A rail_open_spec names a driver ("mock", "gcode", "modbus")
 * and carries every driver's parameters; rail_open() opens the one it names, rail_open_pair()
 * both rails of a rig, two gcode rails on one port sharing one controller link (two axes of one
 * board). The config loaders (config/rail_config.h) fill a spec from a rig file; ribbond opens
 * it here, so opening never goes back up through config/. */
#ifndef RIBBON_DRIVERS_RAIL_OPEN_H
#define RIBBON_DRIVERS_RAIL_OPEN_H

#include <stddef.h>

#include "rail.h"
#include "rail_gcode.h"
#include "rail_mock.h"
#include "rail_modbus.h"

typedef struct rail_open_spec {
    char driver[16];          /* "mock", "gcode" or "modbus" */
    rail_params params;       /* every driver: limits, speeds, gap model */
    rail_gcode_params gcode;  /* driver gcode */
    rail_modbus_params modbus; /* driver modbus */
    rail_mock_params mock;    /* driver mock */
} rail_open_spec;

/* Open the rail a spec names. shared: a GRBL link to use for a gcode rail (NULL: open one). */
rail_err rail_open(const rail_open_spec *s, rail_clock clock, grbl_link *shared, rail **out,
                   char *why, size_t why_len);

/* Open both rails: two gcode rails naming the same port share one controller link (and may not
 * be the same axis). On failure nothing stays open and both outputs are NULL. */
rail_err rail_open_pair(const rail_open_spec *compress_spec, const rail_open_spec *shear_spec,
                        rail_clock clock, rail **compress, rail **shear, char *why, size_t why_len);

#endif
