/* grbl_link.h: private header of the G-code driver: one GRBL controller on one serial port.
 * See grbl_link.c for the flow control. Shared by reference count between axis rails. */
#ifndef RIBBON_DRIVERS_GRBL_LINK_H
#define RIBBON_DRIVERS_GRBL_LINK_H

#include <stdarg.h>
#include <stdbool.h>

#include "grbl_proto.h"
#include "rail_gcode.h"
#include "rail_serial.h"

struct grbl_link {
    rail_serial *ser;
    int refs;
    rail_clock clock;
    double reply_timeout_s;  /* s */
    char rx[256];            /* bytes of the line being assembled */
    size_t rx_len;
    int alarm_code;          /* last ALARM:N seen, 0 = none since the last unlock */
    bool home_pending;       /* "$H" sent, its "ok" not yet seen */
    int home_error;          /* error:N (>0) or -ALARM (<0) ending the homing cycle */
    int resets_seen;         /* reset banners seen (and reconnects: both end any move) */
    double wco[GRBL_MAX_AXES]; /* mm, last work coordinate offset reported */
    bool have_wco;
    bool lost;               /* the port failed: the next status query tries to reopen it */
    char spec[256];          /* port spec, for reopening */
    int baud;
    char why[256];           /* reason of the last failure */
};

rail_err grbl_link_drain(grbl_link *l);
rail_err grbl_link_realtime(grbl_link *l, unsigned char c);
rail_err grbl_link_send(grbl_link *l, const char *cmd, int *err_code);
rail_err grbl_link_status(grbl_link *l, grbl_report *rep);
/* Stop anything the controller is running and empty its planner; never starts motion. */
rail_err grbl_link_quiesce(grbl_link *l, grbl_report *rep);
void grbl_link_retain(grbl_link *l);

#endif
