/* rail_trust.c: the "position not trusted" marker files (see rail_trust.h).
 *
 * File layout, two lines: "instance pty SEC.NSEC" (the pty's ctime) or "instance device", then
 * the reason. Written to a temporary name (O_EXCL | O_NOFOLLOW: the directories may be /tmp) and
 * renamed over the marker, so a reader never sees half a file. */
#define _GNU_SOURCE
#include "rail_trust.h"

#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include "rail_lock_name.h"
#include "rail_serial.h"

/* The instance line of port's device: a pty's names its creation time. */
static void instance_of(const char *port, char *out, size_t n)
{
    char path[256], w[200];
    if (rail_serial_resolve(port, path, sizeof path, w, sizeof w) != RAIL_OK)
        snprintf(path, sizeof path, "%.255s", port);
    struct stat sb;
    /* Unix98 pty slaves: majors 136-143 (Documentation/admin-guide/devices.txt). */
    if (stat(path, &sb) == 0 && S_ISCHR(sb.st_mode) && major(sb.st_rdev) >= 136 && major(sb.st_rdev) <= 143)
        snprintf(out, n, "instance pty %lld.%09ld", (long long)sb.st_ctim.tv_sec, (long)sb.st_ctim.tv_nsec);
    else
        snprintf(out, n, "instance device");
}

static int marker_path(const char *dir, const char *port, char *out, size_t n)
{
    char key[200], name[240];
    rail_lock_serial_key(port, key, sizeof key, name, sizeof name);
    return snprintf(out, n, "%s/ribbon-rig-%s.untrusted", dir, key) < (int)n;
}

void rail_trust_mark(const char *port, const char *why)
{
    char inst[80];
    instance_of(port, inst, sizeof inst);
    const char *dirs[RAIL_LOCK_DIRS];
    int nd = rail_lock_dirs(dirs);
    for (int d = 0; d < nd; d++) {
        char path[512], tmp[560];
        if (access(dirs[d], W_OK) != 0 || !marker_path(dirs[d], port, path, sizeof path)) continue;
        snprintf(tmp, sizeof tmp, "%s.%ld", path, (long)getpid());
        unlink(tmp);
        int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
        if (fd < 0) continue;
        char buf[600];
        int len = snprintf(buf, sizeof buf, "%s\n%.400s\n", inst, why);
        if (len > (int)sizeof buf - 1) len = (int)sizeof buf - 1;
        int ok = write(fd, buf, (size_t)len) == (ssize_t)len;
        ok &= close(fd) == 0;
        if (!ok || rename(tmp, path) != 0) unlink(tmp);
    }
}

int rail_trust_marked(const char *port, char *why, size_t why_len)
{
    char inst[80];
    instance_of(port, inst, sizeof inst);
    const char *dirs[RAIL_LOCK_DIRS];
    int nd = rail_lock_dirs(dirs);
    for (int d = 0; d < nd; d++) {
        char path[512], line1[120] = "", line2[420] = "";
        if (!marker_path(dirs[d], port, path, sizeof path)) continue;
        int fd = open(path, O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
        if (fd < 0) continue;
        FILE *f = fdopen(fd, "r");
        if (!f) {
            close(fd);
            continue;
        }
        if (!fgets(line1, sizeof line1, f)) line1[0] = 0;
        if (!fgets(line2, sizeof line2, f)) line2[0] = 0;
        fclose(f);
        line1[strcspn(line1, "\n")] = 0;
        line2[strcspn(line2, "\n")] = 0;
        if (strcmp(line1, inst) != 0) {
            /* Another pty of that number (an earlier simulator's), or a device that was a pty: not
               this controller's. A marker of a real device always counts. */
            if (strncmp(line1, "instance pty ", 13) == 0) {
                unlink(path);
                continue;
            }
        }
        snprintf(why, why_len, "an earlier process saw: %.300s (%.200s)", line2[0] ? line2 : "position lost",
                 path);
        return 1;
    }
    return 0;
}

void rail_trust_clear(const char *port)
{
    const char *dirs[RAIL_LOCK_DIRS];
    int nd = rail_lock_dirs(dirs);
    for (int d = 0; d < nd; d++) {
        char path[512];
        if (marker_path(dirs[d], port, path, sizeof path)) unlink(path);
    }
}
