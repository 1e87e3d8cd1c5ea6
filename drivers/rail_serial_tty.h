/* rail_serial_tty.h: the termios transport for any terminal device, pseudo-terminals included
 * (which libserialport 0.1.1 refuses) (rail_serial_tty.c). */
#ifndef RIBBON_DRIVERS_RAIL_SERIAL_TTY_H
#define RIBBON_DRIVERS_RAIL_SERIAL_TTY_H

#include <stddef.h>

#include "rail_serial_stream.h"

/* Open path (a terminal device) at baud, 8N1, raw. */
rail_err rail_serial_open_tty(rail_serial **out, const char *path, int baud, char *why, size_t why_len);

#endif
