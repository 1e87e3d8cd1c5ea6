/* rail_trust.h: "position not trusted" kept across processes (issue 34 A).
 *
 * A GRBL controller that reset or raised a position-losing alarm counts from zero wherever its
 * axes stand; the G-code driver then refuses motion until the rail is homed or its zero is
 * confirmed (grbl_link.h). That state lived in the process: a ribbond restarted after the reset
 * found an idle controller, no alarm, and trusted the lost zero. So the link also writes it to a
 * marker file beside the rail's device lock, `ribbon-rig-KEY.untrusted` (KEY as the lock's, in
 * every lock directory rail_lock_dirs() names that this process may write), reads it when it
 * opens, and removes it when the zero is trusted again.
 *
 * Why a file beside the lock and not the store: the state belongs to the device, not to a trial
 * or a daemon; `ribbonctl rail` (which opens no store) and ribbond must both see it; the device
 * lock's key already names a port the same way whatever name reaches it; and the file is written
 * while its device's lock is held. /run/lock is emptied at boot: a rig computer that reboots
 * usually power-cycles a USB-powered board too, which shows its start-up banner on the next open
 * (itself a lost position), but a separately powered board keeps counting: home or confirm after
 * a reboot (docs/rails.md says so).
 *
 * A pseudo-terminal is the far end of a simulator, which dies with it, and the next simulator
 * gets the same pts number: its marker records the pty's creation time too and is ignored (and
 * removed) on any other pty of that number. */
#ifndef RIBBON_DRIVERS_RAIL_TRUST_H
#define RIBBON_DRIVERS_RAIL_TRUST_H

#include <stddef.h>

/* Records that the controller on port lost its position, and why (one line). */
void rail_trust_mark(const char *port, const char *why);
/* 1 when a marker for port stands (why gets its reason and the file's path), else 0. */
int rail_trust_marked(const char *port, char *why, size_t why_len);
/* Removes port's markers (its zero is trusted again: homed or confirmed). */
void rail_trust_clear(const char *port);

#endif
