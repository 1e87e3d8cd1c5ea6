/* rail_serial.h: a byte stream to a serial device, behind a two-entry vtable.
 *
 * Two transports: libserialport for real ports (USB CDC, FTDI...), and plain termios for
 * pseudo-terminals, which libserialport 0.1.1 refuses because it looks every port up under
 * /sys/class/tty. rail_serial_open() tries libserialport first and falls back to termios only
 * for a path that opens as a terminal, so both reasons reach the user if both fail.
 * A port spec is a path ("/dev/ttyACM0", "/dev/pts/5") or "usb:VID:PID[:SERIAL]" (hex VID/PID),
 * resolved against the ports libserialport lists (rail_serial_list). Reads return as soon as
 * any byte is there; a hung-up peer (simulator killed, cable pulled) is RAIL_E_DISCONNECTED.
 * The handle and its calls are rail_serial_stream.h's, each transport has its own header
 * (rail_serial_sp.h also lists ports); this face opens by spec and resolves specs. */
#ifndef RIBBON_DRIVERS_RAIL_SERIAL_H
#define RIBBON_DRIVERS_RAIL_SERIAL_H

#include <stddef.h>

#include "rail_serial_sp.h"
#include "rail_serial_stream.h"

rail_err rail_serial_open(rail_serial **out, const char *spec, int baud, char *why, size_t why_len);

/* Resolve "usb:VID:PID[:SERIAL]" to a path; a plain path is copied as is. */
rail_err rail_serial_resolve(const char *spec, char *path, size_t path_len, char *why, size_t why_len);

#endif
