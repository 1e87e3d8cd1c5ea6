/* rail_serial.h: a byte stream to a serial device, behind a two-entry vtable.
 *
 * Two transports: libserialport for real ports (USB CDC, FTDI...), and plain termios for
 * pseudo-terminals, which libserialport 0.1.1 refuses because it looks every port up under
 * /sys/class/tty. rail_serial_open() tries libserialport first and falls back to termios only
 * for a path that opens as a terminal, so both reasons reach the user if both fail.
 * A port spec is a path ("/dev/ttyACM0", "/dev/pts/5") or "usb:VID:PID[:SERIAL]" (hex VID/PID),
 * resolved against the ports libserialport lists (rail_serial_list). Reads return as soon as
 * any byte is there; a hung-up peer (simulator killed, cable pulled) is RAIL_E_DISCONNECTED. */
#ifndef RIBBON_DRIVERS_RAIL_SERIAL_H
#define RIBBON_DRIVERS_RAIL_SERIAL_H

#include <stddef.h>

#include "rail.h"

typedef struct rail_serial rail_serial;

typedef struct rail_serial_ops {
    const char *name;  /* "libserialport" or "termios" */
    rail_err (*write)(rail_serial *s, const void *buf, size_t n, double timeout_s);
    /* Up to n bytes; *got = 0 with RAIL_OK means the timeout passed with nothing to read. */
    rail_err (*read)(rail_serial *s, void *buf, size_t n, size_t *got, double timeout_s);
    void (*close)(rail_serial *s);
} rail_serial_ops;

struct rail_serial {
    const rail_serial_ops *ops;
    char path[256];      /* resolved device path */
    char why[256];       /* reason of the last failure */
};

rail_err rail_serial_open(rail_serial **out, const char *spec, int baud, char *why, size_t why_len);
rail_err rail_serial_write(rail_serial *s, const void *buf, size_t n, double timeout_s);
rail_err rail_serial_read(rail_serial *s, void *buf, size_t n, size_t *got, double timeout_s);
void rail_serial_close(rail_serial *s);
const char *rail_serial_kind(const rail_serial *s);

/* The two transports, for rail_serial_open and tests. */
rail_err rail_serial_open_sp(rail_serial **out, const char *path, int baud, char *why, size_t n);
rail_err rail_serial_open_tty(rail_serial **out, const char *path, int baud, char *why, size_t n);

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
/* Resolve "usb:VID:PID[:SERIAL]" to a path; a plain path is copied as is. */
rail_err rail_serial_resolve(const char *spec, char *path, size_t path_len, char *why, size_t why_len);

#endif
