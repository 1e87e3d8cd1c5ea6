/* store_full_vfs.h: a full disk on demand for the store's tests: an SQLite VFS shim, made this
 * process's default, that forwards everything to the default VFS except writes, which answer
 * SQLITE_FULL ("database or disk is full") while the fault is on. Every connection opened after
 * the install goes through it (the daemon's and its trial's), so a test can fill the disk in the
 * middle of a trial and free it again, without a small file system. */
#ifndef RIBBON_TESTS_STORE_FULL_VFS_H
#define RIBBON_TESTS_STORE_FULL_VFS_H

/* Registers the shim as the default VFS (once); 0, or -1 when SQLite refused it. */
int store_full_vfs_install(void);
/* 1: every write fails with SQLITE_FULL; 0: writes go through. */
void store_full_vfs_set(int full);
/* Writes refused since the install. */
long store_full_vfs_refused(void);

#endif
