/* check_access.c: may the service user write this path? ribbond runs as its own user (ribbon,
 * groups dialout and video: config/ribbond.service), while `ribbonctl check` is often run by
 * someone else, root included, for whom access(2) says yes to everything. So the answer for
 * another user is worked out from the mode bits, the owner and the user's groups, as the kernel
 * would (owner class first, then group, then other). ACLs and read-only mounts are not seen here:
 * the store's write probe finds those. */
#include <grp.h>
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"

static const char *group_name(gid_t g, char *buf, size_t n)
{
    struct group *gr = getgrgid(g);
    if (gr) snprintf(buf, n, "%s", gr->gr_name);
    else snprintf(buf, n, "%ld", (long)g);
    return buf;
}

static const char *user_name(uid_t u, char *buf, size_t n)
{
    struct passwd *pw = getpwuid(u);
    if (pw) snprintf(buf, n, "%s", pw->pw_name);
    else snprintf(buf, n, "%ld", (long)u);
    return buf;
}

int check_writable_by(const char *path, const char *user, char *why, size_t why_len)
{
    struct stat sb;
    if (stat(path, &sb) != 0) {
        snprintf(why, why_len, "%.300s does not exist", path);
        return -1;
    }
    char on[64], gn[64];
    if (!user) {
        if (access(path, W_OK) == 0) return 0;
        snprintf(why, why_len, "%.300s is not writable by this user (mode %04o, owner %s, group %s)", path,
                 (unsigned)(sb.st_mode & 07777), user_name(sb.st_uid, on, sizeof on),
                 group_name(sb.st_gid, gn, sizeof gn));
        return -1;
    }
    struct passwd *pw = getpwnam(user);
    if (!pw) {
        snprintf(why, why_len, "the service user '%.64s' does not exist (make it: systemd-sysusers, "
                 "docs/install.md), so who may write %.300s is unknown", user, path);
        return -1;
    }
    uid_t uid = pw->pw_uid;
    gid_t gid = pw->pw_gid;
    if (uid == 0) return 0;
    int ok;
    if (sb.st_uid == uid) {
        ok = (sb.st_mode & S_IWUSR) != 0;
    } else {
        gid_t groups[64];
        int ng = 64;
        if (getgrouplist(user, gid, groups, &ng) < 0) ng = 64;
        int in_group = 0;
        for (int i = 0; i < ng && !in_group; i++) in_group = groups[i] == sb.st_gid;
        ok = in_group ? (sb.st_mode & S_IWGRP) != 0 : (sb.st_mode & S_IWOTH) != 0;
    }
    if (ok) return 0;
    snprintf(why, why_len, "%.300s is not writable by user %s (mode %04o, owner %s, group %s)", path, user,
             (unsigned)(sb.st_mode & 07777), user_name(sb.st_uid, on, sizeof on), group_name(sb.st_gid, gn, sizeof gn));
    return -1;
}
