/* rail_gcode_params.h: what a G-code (GRBL) rail is configured with: the controller's port and
 * baud, the axis, the jog segments and the timeouts (rail_gcode_params.c holds the defaults).
 * Both the controller link (grbl_link.h: port, baud, reply timeout) and the axis rail
 * (rail_gcode.h) read it, so it sits below both. */
#ifndef RIBBON_DRIVERS_RAIL_GCODE_PARAMS_H
#define RIBBON_DRIVERS_RAIL_GCODE_PARAMS_H

typedef struct rail_gcode_params {
    char port[256];          /* device path or usb:VID:PID[:SERIAL] */
    int baud;                /* baud, GRBL default 115200 */
    char axis;               /* 'X', 'Y' or 'Z': the controller axis this rail is */
    double segment_s;        /* s of motion per jog segment */
    int segments_ahead;      /* segments queued beyond the current position (1..4) */
    double reply_timeout_s;  /* s to wait for "ok" or a status report */
    double stall_timeout_s;  /* s without progress while moving before a stall fault */
    double boot_wait_s;      /* s, longest wait at open for the controller to answer: an
                                Arduino-based board resets when the port opens and its
                                bootloader listens up to 1 s (Optiboot) before GRBL starts */
    double min_segment_mm;   /* mm, shortest segment (slow jogs): the dead-process bound is
                                segments_ahead * max(segment_s * speed, min_segment_mm) */
} rail_gcode_params;

/* GRBL's defaults: 115200 baud, axis X, 0.3 s segments, 2 ahead, 0.2 s reply, 1 s stall,
 * 2.5 s boot wait. */
rail_gcode_params rail_gcode_params_default(void);

#endif
