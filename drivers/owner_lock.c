/* owner_lock.c: an exclusive flock on a lock file naming its holder (see owner_lock.h). */
#define _GNU_SOURCE
#include "owner_lock.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <time.h>
#include <unistd.h>

struct owner_lock {
    int fd;
};

/* The holder's line as it stands in the file (at most n - 1 bytes, up to its newline); "" when
 * it has not been written yet. */
static void read_holder(int fd, char *out, size_t n)
{
    out[0] = '\0';
    ssize_t got = pread(fd, out, n - 1, 0);
    if (got <= 0) return;
    out[got] = '\0';
    char *nl = strchr(out, '\n');
    if (nl) *nl = '\0';
}

owner_lock *owner_lock_take(const char *path, const char *what, int *held, char *why, size_t why_len)
{
    if (held) *held = 0;
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd < 0) {
        snprintf(why, why_len, "lock file %s cannot be opened: %s", path, strerror(errno));
        return NULL;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        int err = errno;
        if (err == EWOULDBLOCK) {
            if (held) *held = 1;
            char holder[200];
            read_holder(fd, holder, sizeof holder);
            snprintf(why, why_len, "%s is held by %s", path, holder[0] ? holder : "another process");
        } else {
            snprintf(why, why_len, "lock file %s cannot be locked: %s", path, strerror(err));
        }
        close(fd);
        return NULL;
    }
    owner_lock *l = malloc(sizeof *l);
    if (!l) {
        snprintf(why, why_len, "out of memory for the lock %s", path);
        close(fd);
        return NULL;
    }
    l->fd = fd;
    /* Our line replaces the last holder's; a reader that comes between the truncation and the
     * write sees "" and says "another process". */
    char stamp[32] = "?";
    time_t now = time(NULL);
    struct tm tm;
    if (gmtime_r(&now, &tm)) strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%SZ", &tm);
    char line[300];
    int len = snprintf(line, sizeof line, "pid %ld since %s (%.200s)\n", (long)getpid(), stamp,
                       what && *what ? what : "ribbon rig");
    if (len > (int)sizeof line - 1) len = (int)sizeof line - 1;
    if (ftruncate(fd, 0) != 0 || pwrite(fd, line, (size_t)len, 0) != (ssize_t)len) {
        /* The lock holds without its line: others then read "another process". */
    }
    return l;
}

int owner_lock_probe(const char *path, char *why, size_t why_len)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0) return 0;
    int held = 0;
    if (flock(fd, LOCK_SH | LOCK_NB) != 0) {
        held = errno == EWOULDBLOCK;
        if (held) {
            char holder[200];
            read_holder(fd, holder, sizeof holder);
            snprintf(why, why_len, "%s is held by %s", path, holder[0] ? holder : "another process");
        }
    } else {
        flock(fd, LOCK_UN);
    }
    close(fd);
    return held;
}

void owner_lock_release(owner_lock *l)
{
    if (!l) return;
    flock(l->fd, LOCK_UN);
    close(l->fd);
    free(l);
}
