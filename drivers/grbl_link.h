/* grbl_link.h: one GRBL controller on one serial port (grbl_link.c), the G-code driver's link.
 * See grbl_link.c for the flow control. Shared by reference count between axis rails: open one
 * here and pass it to rail_gcode_open for each axis of one controller. */
#ifndef RIBBON_DRIVERS_GRBL_LINK_H
#define RIBBON_DRIVERS_GRBL_LINK_H

#include <stdarg.h>
#include <stdbool.h>

#include "grbl_proto.h"
#include "grbl_settings.h"
#include "rail.h"
#include "rail_gcode_params.h"
#include "rail_serial.h"

typedef struct grbl_link grbl_link;

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
    int own_resets;          /* soft resets (0x18) we sent at rest whose banner is still due */
    double own_reset_t;      /* rail-clock s of the last one: only a banner within the reply
                                timeout (plus GRBL_OWN_RESET_SLACK_S) of it is ours */
    bool zero_lost;          /* the controller's position is not trusted (a reset or an alarm
                                that loses it, since the last homing or confirmed zero) */
    char zero_why[200];      /* what lost it */
    bool critical;           /* "[MSG:Reset to continue]" seen and no banner since: GRBL serves
                                nothing but a reset */
    bool reset_on_open;      /* the controller printed its start-up banner when the port opened */
    grbl_settings settings;  /* the controller's `$$`, read when the link opened */
    double wco[GRBL_MAX_AXES]; /* mm, last work coordinate offset reported */
    bool have_wco;
    bool lost;               /* the port failed: the next status query tries to reopen it */
    char spec[256];          /* port spec, for reopening */
    char key[200];           /* the device's lock key when the port was opened (rail_lock_name.h):
                                the opener's lock (rail_lock.h) covers it */
    char relock_key[200];    /* the key of relock */
    struct rail_port_lock *relock; /* the lock of the device a reopen found instead (USB
                                      re-enumeration: rail_port_lock.h), NULL = none needed */
    int baud;
    char why[256];           /* reason of the last failure */
};

/* s past the reply timeout within which the banner after our own soft reset must come (GRBL
   prints it at once); a later banner is the controller's own restart, whatever we sent. */
#define GRBL_OWN_RESET_SLACK_S 0.5

/* Open a controller link on g's port, baud and reply timeout (the rail_clock times replies). */
rail_err grbl_link_open(grbl_link **out, const rail_gcode_params *g, rail_clock clock, char *why,
                        size_t why_len);
/* Drop one reference; the last closes the port. NULL is a no-op. */
void grbl_link_release(grbl_link *l);

rail_err grbl_link_drain(grbl_link *l);
/* Send "$$" and collect the "$N=V" lines into l->settings (needs the controller at rest). */
rail_err grbl_link_read_settings(grbl_link *l);
/* A soft reset (0x18) we mean to send with the axes at rest: its banner is not a lost position
   (GRBL keeps the machine position over a reset at rest; a reset in motion says ALARM:3). */
rail_err grbl_link_soft_reset(grbl_link *l);
/* Mark the position untrusted (printf-style reason), and trusted again (homed or confirmed). */
void grbl_link_zero_lost(grbl_link *l, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void grbl_link_zero_trusted(grbl_link *l);
rail_err grbl_link_realtime(grbl_link *l, unsigned char c);
rail_err grbl_link_send(grbl_link *l, const char *cmd, int *err_code);
rail_err grbl_link_status(grbl_link *l, grbl_report *rep);
/* Stop anything the controller is running and empty its planner; never starts motion. */
rail_err grbl_link_quiesce(grbl_link *l, grbl_report *rep);
void grbl_link_retain(grbl_link *l);

#endif
