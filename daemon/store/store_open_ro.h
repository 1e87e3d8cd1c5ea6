/* store_open_ro.h: what a read-only open of the store hands to SQLite, so that a WAL store in a
 * directory this user cannot write can still be read, or is refused in words that say why.
 *
 * A WAL database is read through its -shm index, which SQLite creates beside it; in a directory
 * the reader cannot write (a daemon's store read by a lab user, a read-only mount) the read failed
 * as "PRAGMA user_version: unable to open database file" (issue 33). The cases:
 *   - the directory is writable, or the file is not in WAL mode (header bytes 18 and 19 = 2):
 *     the path as it is;
 *   - no -wal file, or an empty one (every page is in the database file: the last connection
 *     closed cleanly): the URI "file:PATH?mode=ro&immutable=1" (SQLite's URI parameters: read
 *     only, no locks, no -shm). immutable means no change is looked for while the file is open:
 *     fine for one read by ribbonctl; a daemon that starts writing meanwhile may give it a stale
 *     or failed read;
 *   - a -wal file with pages and a -shm file beside it: the path (SQLite reads both read-only);
 *   - a -wal file with pages and no -shm: refused, naming the directory and what to do (those
 *     pages cannot be read without the index, and immutable would ignore them). */
#ifndef RIBBON_DAEMON_STORE_OPEN_RO_H
#define RIBBON_DAEMON_STORE_OPEN_RO_H

#include <stddef.h>

/* Writes the name to open (a path or a file: URI) into target. *uri = 1 when it is a URI (open it
 * with SQLITE_OPEN_URI). Returns 0, or -1 with the reason in why. */
int store_open_ro_target(const char *path, char *target, size_t target_len, int *uri, char *why, size_t why_len);

#endif
