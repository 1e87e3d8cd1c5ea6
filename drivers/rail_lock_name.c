/* rail_lock_name.c: the lock directories and a serial port's lock key (see rail_lock_name.h). */
#include "rail_lock_name.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include "rail_serial.h"

const char *rail_lock_dir(void)
{
    const char *env = getenv("RIBBON_LOCK_DIR");
    if (env && *env) return env;
    struct stat sb;
    if (stat("/run/lock", &sb) == 0 && S_ISDIR(sb.st_mode) && access("/run/lock", W_OK) == 0) return "/run/lock";
    return "/tmp";
}

int rail_lock_dirs(const char *dirs[RAIL_LOCK_DIRS])
{
    int n = 0;
    const char *cand[RAIL_LOCK_DIRS + 1] = {rail_lock_dir(), getenv("RIBBON_LOCK_DIR"), "/run/lock", "/tmp"};
    for (int i = 0; i <= RAIL_LOCK_DIRS && n < RAIL_LOCK_DIRS; i++) {
        const char *d = cand[i];
        struct stat sb;
        if (!d || !*d || (i > 0 && (stat(d, &sb) != 0 || !S_ISDIR(sb.st_mode)))) continue;
        int seen = 0;
        for (int k = 0; k < n; k++) seen |= !strcmp(dirs[k], d);
        if (!seen) dirs[n++] = d;
    }
    return n;
}

/* Letters, digits, '.' and '-' of text, every other byte '_' (a file name from an address). */
void rail_lock_sanitize(char *out, size_t n, const char *text)
{
    size_t k = 0;
    for (; text[k] && k + 1 < n; k++) {
        char c = text[k];
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '-';
        out[k] = ok ? c : '_';
    }
    out[k] = '\0';
}

void rail_lock_serial_key(const char *serial, char *key, size_t key_len, char *name, size_t name_len)
{
    char path[256], w[200];
    if (rail_serial_resolve(serial, path, sizeof path, w, sizeof w) != RAIL_OK)
        snprintf(path, sizeof path, "%.255s", serial); /* opening it will say why */
    snprintf(name, name_len, "serial port %.200s", path);
    struct stat sb;
    if (stat(path, &sb) == 0 && S_ISCHR(sb.st_mode)) {
        snprintf(key, key_len, "serial-%u-%u", major(sb.st_rdev), minor(sb.st_rdev));
    } else {
        char t[200];
        rail_lock_sanitize(t, sizeof t, path);
        snprintf(key, key_len, "serial-path-%.150s", t);
    }
}
