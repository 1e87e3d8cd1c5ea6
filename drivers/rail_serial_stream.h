/* rail_serial_stream.h: the byte-stream handle every serial transport fills in: a two-entry
 * vtable (write, read) plus close, the resolved path and the last failure's reason, and the calls
 * through it. The transports (rail_serial_sp.c, rail_serial_tty.c) include this header and
 * nothing above it; rail_serial.h, the family's face, chooses between them. */
#ifndef RIBBON_DRIVERS_RAIL_SERIAL_STREAM_H
#define RIBBON_DRIVERS_RAIL_SERIAL_STREAM_H

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

rail_err rail_serial_write(rail_serial *s, const void *buf, size_t n, double timeout_s);
rail_err rail_serial_read(rail_serial *s, void *buf, size_t n, size_t *got, double timeout_s);
void rail_serial_close(rail_serial *s);
const char *rail_serial_kind(const rail_serial *s);

#endif
