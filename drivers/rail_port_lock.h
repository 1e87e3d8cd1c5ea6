/* rail_port_lock.h: one serial port's device lock taken by the G-code link itself, when it
 * reopens its port and finds another device behind the same name (USB re-enumeration).
 *
 * ribbond and ribbonctl lock each rail's device before they open it (rail_lock.h), keyed on the
 * character device's numbers. A USB-serial adapter that drops off the bus and comes back may get
 * another number (/dev/ttyUSB0 becomes /dev/ttyUSB1; a by-id link or usb:VID:PID follows it), and
 * the link's reopen follows the name: the lock held is then on a device number nobody uses, and a
 * second daemon could lock and drive the new one. So a reopen that lands on another key takes that
 * key's lock (in the same directories and the same way as rail_lock.h) before it sends anything,
 * and holds it while the link lives; held by another process, the reopen is refused naming the
 * lock file found held. */
#ifndef RIBBON_DRIVERS_RAIL_PORT_LOCK_H
#define RIBBON_DRIVERS_RAIL_PORT_LOCK_H

#include <stddef.h>

typedef struct rail_port_lock rail_port_lock;

/* The lock of port's device (key as rail_lock_serial_key gives it), what going into the holder's
 * line. NULL with why (and *held = 1 when another process holds it). */
rail_port_lock *rail_port_lock_take(const char *port, const char *what, int *held, char *why, size_t why_len);
/* NULL is a no-op. */
void rail_port_lock_release(rail_port_lock *l);

#endif
