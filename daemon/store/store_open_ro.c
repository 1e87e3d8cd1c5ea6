/* store_open_ro.c: choosing what a read-only open hands to SQLite (see store_open_ro.h). */
#include "store_open_ro.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The directory of path (without a trailing slash; "." for a bare name). */
static void dir_of(const char *path, char *dir, size_t len)
{
    snprintf(dir, len, "%s", path);
    char *slash = strrchr(dir, '/');
    if (!slash) snprintf(dir, len, ".");
    else if (slash == dir) slash[1] = '\0';
    else *slash = '\0';
}

/* Whether the file's header says WAL (file format versions 2 and 2 at offsets 18 and 19). */
static int is_wal(const char *path)
{
    unsigned char h[20];
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    size_t n = fread(h, 1, sizeof h, f);
    fclose(f);
    return n == sizeof h && h[18] == 2 && h[19] == 2;
}

/* "file:" + path with the characters a URI path cannot hold as they are percent-encoded. */
static int uri_of(const char *path, char *out, size_t len)
{
    static const char hex[] = "0123456789ABCDEF";
    size_t k = 0;
    const char *head = "file:";
    for (const char *p = head; *p; p++) {
        if (k + 1 >= len) return -1;
        out[k++] = *p;
    }
    for (const unsigned char *p = (const unsigned char *)path; *p; p++) {
        int plain = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') ||
                    strchr("/-._~", *p) != NULL;
        if (k + (plain ? 1 : 3) >= len) return -1;
        if (plain) {
            out[k++] = (char)*p;
        } else {
            out[k++] = '%';
            out[k++] = hex[*p >> 4];
            out[k++] = hex[*p & 15];
        }
    }
    const char *tail = "?mode=ro&immutable=1";
    for (const char *p = tail; *p; p++) {
        if (k + 1 >= len) return -1;
        out[k++] = *p;
    }
    out[k] = '\0';
    return 0;
}

int store_open_ro_target(const char *path, char *target, size_t target_len, int *uri, char *why, size_t why_len)
{
    char dir[1024], wal[1100], shm[1100];
    *uri = 0;
    dir_of(path, dir, sizeof dir);
    if (access(dir, W_OK) == 0 || !is_wal(path)) {
        snprintf(target, target_len, "%s", path);
        return 0;
    }
    snprintf(wal, sizeof wal, "%s-wal", path);
    snprintf(shm, sizeof shm, "%s-shm", path);
    struct stat sw;
    if (stat(wal, &sw) != 0 || sw.st_size == 0) {
        if (uri_of(path, target, target_len) != 0) {
            snprintf(why, why_len, "store %.300s: path too long to open read-only", path);
            return -1;
        }
        *uri = 1;
        return 0;
    }
    if (access(shm, R_OK) == 0) {
        snprintf(target, target_len, "%s", path);
        return 0;
    }
    snprintf(why, why_len,
             "store %.300s is a WAL store with pages still in %.300s-wal, and its directory %.300s is not "
             "writable, so SQLite cannot make the index it reads them with: a WAL store needs a writable "
             "directory (read a copy of both files elsewhere, or let the program that wrote them close the "
             "store, which folds the -wal file into it)",
             path, path, dir);
    return -1;
}
