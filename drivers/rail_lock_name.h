/* rail_lock_name.h: where the rails' device locks live and what they are called (rail_lock.h
 * takes them; rail_trust.h keeps its markers beside them). Kept apart from rail_lock.h, which
 * knows the driver factory's specs, so that a driver's own link can name its device's files
 * without including the factory above it. */
#ifndef RIBBON_DRIVERS_RAIL_LOCK_NAME_H
#define RIBBON_DRIVERS_RAIL_LOCK_NAME_H

#include <stddef.h>

/* The lock directory: $RIBBON_LOCK_DIR when set, else /run/lock when it is a writable directory
 * (Debian's, shared by every user), else /tmp. */
const char *rail_lock_dir(void);

/* Every directory a ribbond or a ribbonctl may resolve as its lock directory, without repeats:
 * rail_lock_dir() first, then $RIBBON_LOCK_DIR, /run/lock and /tmp (those that are directories).
 * Returns how many (at most RAIL_LOCK_DIRS). */
#define RAIL_LOCK_DIRS 3
int rail_lock_dirs(const char *dirs[RAIL_LOCK_DIRS]);

/* Letters, digits, '.' and '-' of text, every other byte '_' (a file name from an address). */
void rail_lock_sanitize(char *out, size_t n, const char *text);

/* The lock key of a serial port (a device path, a symlink, usb:VID:PID): "serial-MAJOR-MINOR"
 * for a character device, else "serial-path-TEXT"; name gets "serial port PATH". */
void rail_lock_serial_key(const char *port, char *key, size_t key_len, char *name, size_t name_len);

#endif
