/* rail_port_lock.c: a serial port's device lock for the link's reopen (see rail_port_lock.h). */
#include "rail_port_lock.h"

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "owner_lock.h"
#include "rail_lock_name.h"

struct rail_port_lock {
    owner_lock *held[RAIL_LOCK_DIRS];
    int n;
};

void rail_port_lock_release(rail_port_lock *l)
{
    if (!l) return;
    for (int k = 0; k < l->n; k++) owner_lock_release(l->held[k]);
    free(l);
}

rail_port_lock *rail_port_lock_take(const char *port, const char *what, int *held, char *why, size_t why_len)
{
    if (held) *held = 0;
    rail_port_lock *l = calloc(1, sizeof *l);
    if (!l) {
        snprintf(why, why_len, "out of memory for a port's lock");
        return NULL;
    }
    char key[200], name[240];
    rail_lock_serial_key(port, key, sizeof key, name, sizeof name);
    const char *dirs[RAIL_LOCK_DIRS];
    int nd = rail_lock_dirs(dirs);
    for (int d = 0; d < nd; d++) {
        char path[512], w[600];
        snprintf(path, sizeof path, "%s/ribbon-rig-%s.lock", dirs[d], key);
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
        if (d > 0 && !busy) continue;
        snprintf(why, why_len, "%s%s", busy ? "in use: " : "", w); /* w names the lock file */
        (void)name;
        if (held) *held = busy;
        rail_port_lock_release(l);
        return NULL;
    }
    return l;
}
