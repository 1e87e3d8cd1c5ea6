/* rail_lock.h: the locks on the devices a rig's two rails name, so that two daemons never drive
 * one controller or drive (issue 33, item 1: a second ribbond opened the same GRBL pty and the
 * first one's shear failed with a stall).
 *
 * One owner lock (owner_lock.h) per device, taken before the device is opened, in the lock
 * directory (rail_lock_dir), in a file named after the device:
 *   serial port (gcode, Modbus RTU)  ribbon-rig-serial-MAJOR-MINOR.lock: the character device's
 *                                    numbers, so every name of one port (/dev/ttyUSB0, a by-id
 *                                    link, usb:VID:PID, a symlink to a pty) is one lock; a path
 *                                    that does not exist yet is keyed on its text;
 *   Modbus TCP drive                 ribbon-rig-modbus-HOST-PORT.lock (the address as written:
 *                                    libmodbus takes a numeric IPv4 address);
 *   mock rail                        no device, no lock.
 * Two rails on one device (two GRBL axes of one controller, two drives on one RS-485 line) take
 * its lock once.
 * A ribbond under systemd (its unit's environment) and a ribbonctl from a shell may resolve
 * different lock directories (RIBBON_LOCK_DIR set for one only, or /run/lock writable for one
 * only). So the device's lock file is also taken in every other candidate directory
 * ($RIBBON_LOCK_DIR, /run/lock, /tmp) this process may write, and tested (a read-only flock
 * probe) in those it may not: whichever directory the other process uses, one of the two finds
 * the other's lock, and its refusal names the lock file it found held. */
#ifndef RIBBON_DRIVERS_RAIL_LOCK_H
#define RIBBON_DRIVERS_RAIL_LOCK_H

#include <stddef.h>

#include "rail.h"
#include "rail_lock_name.h"
#include "rail_open.h"

typedef struct rail_locks rail_locks;

/* Takes the locks of both rails' devices; what goes into the holder's line. RAIL_OK with *out
 * (NULL when no rail names a device), or RAIL_E_STATE with why naming the rail, the device and
 * the holder ("rail shear: serial port /dev/ttyUSB0 is in use: LOCKFILE is held by pid 1234 since
 * ..."), or RAIL_E_IO when a lock file cannot be made; then no lock is held. */
rail_err rail_locks_take(const rail_open_spec *compress, const rail_open_spec *shear, const char *what,
                         rail_locks **out, char *why, size_t why_len);
/* Releases every lock. NULL is a no-op. */
void rail_locks_release(rail_locks *l);

#endif
