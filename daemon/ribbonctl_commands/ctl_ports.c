/* ctl_ports.c: `ribbonctl ports [--json]`: the serial ports libserialport sees, with USB VID:PID
 * and serial number, so a rail can be configured as usb:VID:PID[:SERIAL] and survive renumbering.
 * Pseudo-terminals (simulators) are not listed: libserialport does not see them. */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctl.h"
#include "rail_serial.h"

int ctl_ports_main(int argc, char **argv)
{
    int json = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--json")) {
            json = 1;
        } else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            printf("usage: ribbonctl ports [--json]\n");
            return 0;
        } else {
            fprintf(stderr, "ribbonctl ports: unknown option '%s'\n", argv[i]);
            return 2;
        }
    }
    enum { MAXP = 128 };
    rail_serial_port_info *ports = calloc(MAXP, sizeof *ports);
    if (!ports) {
        fprintf(stderr, "ribbonctl ports: out of memory\n");
        return 1;
    }
    size_t n = 0;
    char why[256] = "";
    if (rail_serial_list(ports, MAXP, &n, why, sizeof why) != RAIL_OK) {
        fprintf(stderr, "ribbonctl ports: %s\n", why);
        free(ports);
        return 1;
    }
    if (json) {
        json_t *arr = json_array();
        for (size_t i = 0; i < n; i++) {
            json_t *o = json_object();
            json_object_set_new(o, "path", json_string(ports[i].path));
            json_object_set_new(o, "transport", json_string(ports[i].transport));
            json_object_set_new(o, "description", json_string(ports[i].description));
            if (ports[i].usb_vid >= 0) {
                char spec[96];
                snprintf(spec, sizeof spec, "usb:%04x:%04x%s%s", ports[i].usb_vid, ports[i].usb_pid,
                         ports[i].serial[0] ? ":" : "", ports[i].serial);
                json_object_set_new(o, "usb_vid", json_integer(ports[i].usb_vid));
                json_object_set_new(o, "usb_pid", json_integer(ports[i].usb_pid));
                json_object_set_new(o, "serial", json_string(ports[i].serial));
                json_object_set_new(o, "spec", json_string(spec));
            }
            json_array_append_new(arr, o);
        }
        char *s = json_dumps(arr, JSON_COMPACT);
        printf("%s\n", s ? s : "[]");
        free(s);
        json_decref(arr);
    } else if (n == 0) {
        printf("no serial ports found\n");
    } else {
        for (size_t i = 0; i < n; i++) {
            if (ports[i].usb_vid >= 0)
                printf("%-20s usb:%04x:%04x%s%-16s %s\n", ports[i].path, ports[i].usb_vid, ports[i].usb_pid,
                       ports[i].serial[0] ? ":" : " ", ports[i].serial, ports[i].description);
            else
                printf("%-20s %-26s %s\n", ports[i].path, ports[i].transport, ports[i].description);
        }
    }
    free(ports);
    return 0;
}
