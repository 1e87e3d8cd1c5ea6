/* rail_lock.c: the rails' device locks (see rail_lock.h). */
#include "rail_lock.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include "owner_lock.h"
#include "rail_serial.h"

/* One device per rail at most, each locked in up to RAIL_LOCK_DIRS directories. */
#define RAIL_LOCK_DIRS 3
#define RAIL_LOCK_MAX (2 * RAIL_LOCK_DIRS)

struct rail_locks {
    owner_lock *held[RAIL_LOCK_MAX];
    int n;
};

const char *rail_lock_dir(void)
{
    const char *env = getenv("RIBBON_LOCK_DIR");
    if (env && *env) return env;
    struct stat sb;
    if (stat("/run/lock", &sb) == 0 && S_ISDIR(sb.st_mode) && access("/run/lock", W_OK) == 0) return "/run/lock";
    return "/tmp";
}

/* Every directory a ribbond or a ribbonctl may resolve as its lock directory: $RIBBON_LOCK_DIR
 * (when set), /run/lock (when a directory) and /tmp, without repeats. The first is ours. */
static int lock_dirs(const char *dirs[RAIL_LOCK_DIRS])
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
static void sanitize(char *out, size_t n, const char *text)
{
    size_t k = 0;
    for (; text[k] && k + 1 < n; k++) {
        char c = text[k];
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '-';
        out[k] = ok ? c : '_';
    }
    out[k] = '\0';
}

/* The device a spec names: a key for its lock file and its name for messages; 0 when it names
 * none (mock). */
static int device_key(const rail_open_spec *s, char *key, size_t key_len, char *name, size_t name_len)
{
    const char *serial = NULL;
    if (!strcmp(s->driver, "gcode"))
        serial = s->gcode.port;
    else if (!strcmp(s->driver, "modbus") && s->modbus.rtu)
        serial = s->modbus.address;
    else if (!strcmp(s->driver, "modbus")) {
        char a[128];
        sanitize(a, sizeof a, s->modbus.address);
        snprintf(key, key_len, "modbus-%.150s", a);
        snprintf(name, name_len, "Modbus drive %.160s", s->modbus.address);
        return 1;
    } else
        return 0;
    char path[256], w[200];
    if (rail_serial_resolve(serial, path, sizeof path, w, sizeof w) != RAIL_OK)
        snprintf(path, sizeof path, "%.255s", serial); /* opening it will say why */
    snprintf(name, name_len, "serial port %.200s", path);
    struct stat sb;
    if (stat(path, &sb) == 0 && S_ISCHR(sb.st_mode)) {
        snprintf(key, key_len, "serial-%u-%u", major(sb.st_rdev), minor(sb.st_rdev));
    } else {
        char t[200];
        sanitize(t, sizeof t, path);
        snprintf(key, key_len, "serial-path-%.150s", t);
    }
    return 1;
}

void rail_locks_release(rail_locks *l)
{
    if (!l) return;
    for (int k = 0; k < l->n; k++) owner_lock_release(l->held[k]);
    free(l);
}

rail_err rail_locks_take(const rail_open_spec *compress, const rail_open_spec *shear, const char *what,
                         rail_locks **out, char *why, size_t why_len)
{
    *out = NULL;
    const rail_open_spec *spec[2] = {compress, shear};
    char keys[2][200];
    rail_locks *l = calloc(1, sizeof *l);
    if (!l) {
        snprintf(why, why_len, "out of memory for the rails' locks");
        return RAIL_E_NOMEM;
    }
    for (int r = 0; r < 2; r++) {
        char name[240];
        keys[r][0] = '\0';
        if (!spec[r] || !device_key(spec[r], keys[r], sizeof keys[r], name, sizeof name)) continue;
        if (r == 1 && !strcmp(keys[0], keys[1])) continue; /* one device, one lock */
        /* Ours first; then the device's lock file in every other directory another process may
         * have resolved (its environment or its rights differ): taken there too where we may
         * write, so it finds us whichever it uses; tested without taking where we may not. */
        const char *dirs[RAIL_LOCK_DIRS];
        int nd = lock_dirs(dirs);
        for (int d = 0; d < nd; d++) {
            char path[512], w[600];
            snprintf(path, sizeof path, "%s/ribbon-rig-%s.lock", dirs[d], keys[r]);
            int busy = 0;
            owner_lock *ol = NULL;
            if (d == 0 || access(dirs[d], W_OK) == 0)
                ol = owner_lock_take(path, what, &busy, w, sizeof w);
            else
                busy = owner_lock_probe(path, w, sizeof w);
            if (ol) {
                l->held[l->n++] = ol;
                continue;
            }
            if (d > 0 && !busy) continue; /* another directory's file we cannot make: not ours */
            snprintf(why, why_len, "rail %s: %s %s: %s", spec[r]->params.name[0] ? spec[r]->params.name : "?", name,
                     busy ? "is in use" : "cannot be locked", w);
            rail_locks_release(l);
            return busy ? RAIL_E_STATE : RAIL_E_IO;
        }
    }
    if (l->n == 0) {
        free(l);
        l = NULL;
    }
    *out = l;
    return RAIL_OK;
}
