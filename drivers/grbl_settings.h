/* grbl_settings.h: a GRBL 1.1 controller's settings as `$$` lists them ("$N=V" lines), and the
 * check of what the G-code driver depends on against one rail's configuration.
 *
 * Pure functions over text and numbers, no I/O: the link reads the lines (grbl_link.c), the
 * simulator keeps its own table (grbl_sim.c), the tests call the check directly. Meanings and
 * units follow GRBL 1.1's settings documentation (doc/markdown/settings.md and
 * doc/csv/setting_codes_en_US.csv of the GRBL project): $10 status report mask (bit 0: 1 = MPos,
 * 0 = WPos), $13 report inches, $20 soft limits, $21 hard limits, $22 homing cycle, $3 direction
 * invert mask, $110-$112 max rate (mm/min), $120-$122 acceleration (mm/sec^2), $130-$132 max
 * travel (mm). */
#ifndef RIBBON_DRIVERS_GRBL_SETTINGS_H
#define RIBBON_DRIVERS_GRBL_SETTINGS_H

#include <stdbool.h>
#include <stddef.h>

#include "rail.h"

#define GRBL_SETTING_MAX 133 /* $0 .. $132 */

typedef struct grbl_settings {
    double v[GRBL_SETTING_MAX];   /* the value of $N, in the setting's own unit */
    bool have[GRBL_SETTING_MAX];  /* $N was listed */
    int count;                    /* settings listed */
} grbl_settings;

/* Parse one "$N=V" line (as `$$` prints it); false if it is not one. */
bool grbl_setting_line_parse(const char *line, size_t len, int *num, double *val);
/* Record one setting (ignored when num is out of range). */
void grbl_settings_set(grbl_settings *s, int num, double val);
/* The settings as one line "$0=10 $1=25 ... $132=200" (for a trial's record); returns length. */
size_t grbl_settings_format(const grbl_settings *s, char *buf, size_t n);

/* The outcome of checking a controller's settings for one rail. */
typedef struct grbl_settings_check_out {
    bool refuse;          /* the driver cannot work with these settings: refuse names why */
    char refuse_why[480]; /* the setting, its value and what to set */
    double accel_mm_s2;   /* mm/s^2: the axis's $12x, adopted as the rail's acceleration */
    bool homing;          /* $22=1: after a reset the rail must be homed ($H) before it moves */
    bool work_pos;        /* $10 bit 0 = 0: the controller reports WPos (plus WCO now and then) */
    char warn[600];       /* adopted or tolerated settings worth a line in the log ("" = none) */
} grbl_settings_check_out;

/* Check the settings the driver depends on for the axis (0 = X, 1 = Y, 2 = Z) of a rail with
 * parameters p (speed limit, acceleration, soft limits; name for the messages). Refused: a
 * setting missing from `$$`, $13=1 (inches), max rate $11x below the rail's max_speed_mm_s.
 * Adopted with a warning: $12x different from accel_mm_s2 by more than 1%, $10 bit 0 = 0
 * (WPos). Warned: soft limits off ($20=0) or their travel $13x shorter than the rail's soft
 * range, hard limits off ($21=0). */
void grbl_settings_check(const grbl_settings *s, int axis, const rail_params *p,
                         grbl_settings_check_out *out);

#endif
