/* rail_serial_sp.h: the libserialport transport (real ports: USB CDC, FTDI...) and the port
 * list libserialport gives (rail_serial_sp.c). */
#ifndef RIBBON_DRIVERS_RAIL_SERIAL_SP_H
#define RIBBON_DRIVERS_RAIL_SERIAL_SP_H

#include <stddef.h>

#include "rail_serial_stream.h"

/* Open path (already resolved) at baud, 8N1, no flow control. */
rail_err rail_serial_open_sp(rail_serial **out, const char *path, int baud, char *why, size_t why_len);

/* One port as libserialport lists it. */
typedef struct rail_serial_port_info {
    char path[128];
    char description[128];
    char transport[16];   /* "usb", "bluetooth", "native" */
    int usb_vid, usb_pid; /* -1 when not USB */
    char serial[64];      /* USB serial number, "" if none */
} rail_serial_port_info;

/* Fill up to max entries; *count gets how many were listed. */
rail_err rail_serial_list(rail_serial_port_info *ports, size_t max, size_t *count, char *why,
                          size_t why_len);
#endif
