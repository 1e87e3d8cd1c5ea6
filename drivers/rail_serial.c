/* rail_serial.c: choosing a serial transport and resolving "usb:VID:PID[:SERIAL]" specs.
 * See rail_serial.h for why there are two transports. */
#include "rail_serial.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rail_serial_tty.h"

rail_err rail_serial_resolve(const char *spec, char *path, size_t path_len, char *why, size_t why_len)
{
    if (!spec || !spec[0]) {
        snprintf(why, why_len, "serial port not given");
        return RAIL_E_INVALID;
    }
    if (strncmp(spec, "usb:", 4) != 0) {
        if (strlen(spec) >= path_len) {
            snprintf(why, why_len, "serial port path too long");
            return RAIL_E_INVALID;
        }
        rail_text_copy(path, path_len, spec);
        return RAIL_OK;
    }
    unsigned vid = 0, pid = 0;
    char serial[64] = "";
    int k = sscanf(spec + 4, "%4x:%4x:%63s", &vid, &pid, serial);
    if (k < 2) {
        snprintf(why, why_len, "port spec '%.60s' is not usb:VID:PID[:SERIAL] with hex VID, PID", spec);
        return RAIL_E_INVALID;
    }
    enum { MAXP = 64 };
    rail_serial_port_info *ports = calloc(MAXP, sizeof *ports);
    if (!ports) {
        snprintf(why, why_len, "out of memory listing ports");
        return RAIL_E_NOMEM;
    }
    size_t n = 0, found = 0;
    rail_err e = rail_serial_list(ports, MAXP, &n, why, why_len);
    for (size_t i = 0; e == RAIL_OK && i < n && i < MAXP; i++) {
        if (ports[i].usb_vid != (int)vid || ports[i].usb_pid != (int)pid)
            continue;
        if (serial[0] && strcmp(serial, ports[i].serial) != 0)
            continue;
        if (found++ == 0)
            rail_text_copy(path, path_len, ports[i].path);
    }
    free(ports);
    if (e != RAIL_OK)
        return e;
    if (found == 0) {
        snprintf(why, why_len, "no serial port with USB %04x:%04x%s%s (see `ribbonctl ports`)", vid,
                 pid, serial[0] ? " serial " : "", serial);
        return RAIL_E_IO;
    }
    if (found > 1) {
        snprintf(why, why_len, "%zu ports match USB %04x:%04x; add the serial number", found, vid, pid);
        return RAIL_E_INVALID;
    }
    return RAIL_OK;
}

rail_err rail_serial_open(rail_serial **out, const char *spec, int baud, char *why, size_t why_len)
{
    *out = NULL;
    char path[256];
    rail_err e = rail_serial_resolve(spec, path, sizeof path, why, why_len);
    if (e != RAIL_OK)
        return e;
    char why_sp[256] = "", why_tty[256] = "";
    e = rail_serial_open_sp(out, path, baud, why_sp, sizeof why_sp);
    if (e == RAIL_OK)
        return e;
    /* libserialport refuses pseudo-terminals; the termios path takes any terminal device. */
    e = rail_serial_open_tty(out, path, baud, why_tty, sizeof why_tty);
    if (e == RAIL_OK)
        return e;
    snprintf(why, why_len, "cannot open %.100s: libserialport: %.120s; termios: %.120s", path, why_sp,
             why_tty);
    return e;
}
