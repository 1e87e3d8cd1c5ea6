/* rail_lock.c: the rails' device locks (see rail_lock.h). */
#include "rail_lock.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "owner_lock.h"

/* One device per rail at most, each locked in up to RAIL_LOCK_DIRS directories. */
#define RAIL_LOCK_MAX (2 * RAIL_LOCK_DIRS)

struct rail_locks {
    owner_lock *held[RAIL_LOCK_MAX];
    int n;
};

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
        rail_lock_sanitize(a, sizeof a, s->modbus.address);
        snprintf(key, key_len, "modbus-%.150s", a);
        snprintf(name, name_len, "Modbus drive %.160s", s->modbus.address);
        return 1;
    } else
        return 0;
    rail_lock_serial_key(serial, key, key_len, name, name_len);
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
        int nd = rail_lock_dirs(dirs);
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
