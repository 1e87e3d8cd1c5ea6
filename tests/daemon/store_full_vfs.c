/* store_full_vfs.c: the full-disk VFS shim (see store_full_vfs.h). Each file is the default
 * VFS's file placed right after our header; every method forwards to it. */
#include "store_full_vfs.h"

#include <sqlite3.h>
#include <stdatomic.h>
#include <string.h>

typedef struct full_file {
    sqlite3_file base;
    sqlite3_file *real; /* right after this struct */
} full_file;

static sqlite3_vfs *real_vfs;
static sqlite3_vfs full_vfs;
static atomic_int full_on;
static atomic_long refused;

#define REAL(f) (((full_file *)(f))->real)

static int f_close(sqlite3_file *f) { return REAL(f)->pMethods->xClose(REAL(f)); }
static int f_read(sqlite3_file *f, void *b, int n, sqlite3_int64 o) { return REAL(f)->pMethods->xRead(REAL(f), b, n, o); }
static int f_write(sqlite3_file *f, const void *b, int n, sqlite3_int64 o)
{
    if (atomic_load(&full_on)) {
        atomic_fetch_add(&refused, 1);
        return SQLITE_FULL;
    }
    return REAL(f)->pMethods->xWrite(REAL(f), b, n, o);
}
static int f_truncate(sqlite3_file *f, sqlite3_int64 n) { return REAL(f)->pMethods->xTruncate(REAL(f), n); }
static int f_sync(sqlite3_file *f, int flags) { return REAL(f)->pMethods->xSync(REAL(f), flags); }
static int f_size(sqlite3_file *f, sqlite3_int64 *n) { return REAL(f)->pMethods->xFileSize(REAL(f), n); }
static int f_lock(sqlite3_file *f, int l) { return REAL(f)->pMethods->xLock(REAL(f), l); }
static int f_unlock(sqlite3_file *f, int l) { return REAL(f)->pMethods->xUnlock(REAL(f), l); }
static int f_reserved(sqlite3_file *f, int *r) { return REAL(f)->pMethods->xCheckReservedLock(REAL(f), r); }
static int f_control(sqlite3_file *f, int op, void *a) { return REAL(f)->pMethods->xFileControl(REAL(f), op, a); }
static int f_sector(sqlite3_file *f) { return REAL(f)->pMethods->xSectorSize(REAL(f)); }
static int f_device(sqlite3_file *f) { return REAL(f)->pMethods->xDeviceCharacteristics(REAL(f)); }
static int f_shm_map(sqlite3_file *f, int pg, int sz, int ext, void volatile **p)
{
    return REAL(f)->pMethods->xShmMap(REAL(f), pg, sz, ext, p);
}
static int f_shm_lock(sqlite3_file *f, int off, int n, int flags)
{
    return REAL(f)->pMethods->xShmLock(REAL(f), off, n, flags);
}
static void f_shm_barrier(sqlite3_file *f) { REAL(f)->pMethods->xShmBarrier(REAL(f)); }
static int f_shm_unmap(sqlite3_file *f, int del) { return REAL(f)->pMethods->xShmUnmap(REAL(f), del); }
static int f_fetch(sqlite3_file *f, sqlite3_int64 o, int n, void **p) { return REAL(f)->pMethods->xFetch(REAL(f), o, n, p); }
static int f_unfetch(sqlite3_file *f, sqlite3_int64 o, void *p) { return REAL(f)->pMethods->xUnfetch(REAL(f), o, p); }

static const sqlite3_io_methods full_io = {
    3, f_close, f_read, f_write, f_truncate, f_sync, f_size, f_lock, f_unlock, f_reserved, f_control, f_sector,
    f_device, f_shm_map, f_shm_lock, f_shm_barrier, f_shm_unmap, f_fetch, f_unfetch,
};

static int full_open(sqlite3_vfs *vfs, const char *name, sqlite3_file *file, int flags, int *out_flags)
{
    (void)vfs;
    full_file *ff = (full_file *)file;
    ff->real = (sqlite3_file *)(ff + 1);
    memset(ff->real, 0, (size_t)real_vfs->szOsFile);
    file->pMethods = NULL;
    int rc = real_vfs->xOpen(real_vfs, name, ff->real, flags, out_flags);
    if (ff->real->pMethods) file->pMethods = &full_io; /* closed through us even after a failure */
    return rc;
}

int store_full_vfs_install(void)
{
    if (real_vfs) return 0;
    sqlite3_vfs *def = sqlite3_vfs_find(NULL);
    if (!def || def->iVersion < 1) return -1;
    /* The unix VFS's file methods are version 3 (shared memory for WAL, memory mapping). */
    full_vfs = *def;
    full_vfs.szOsFile = (int)sizeof(full_file) + def->szOsFile;
    full_vfs.zName = "ribbon-full-disk";
    full_vfs.xOpen = full_open;
    full_vfs.pNext = NULL;
    real_vfs = def;
    if (sqlite3_vfs_register(&full_vfs, 1) != SQLITE_OK) {
        real_vfs = NULL;
        return -1;
    }
    return 0;
}

void store_full_vfs_set(int full) { atomic_store(&full_on, full ? 1 : 0); }

long store_full_vfs_refused(void) { return atomic_load(&refused); }
