/* rail_serial_sp.c: the libserialport transport for real serial ports, and port listing.
 * 8N1, no flow control. Timeouts are passed to libserialport in milliseconds (at least 1). */
#include <libserialport.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rail_serial_sp.h"

typedef struct sp_serial {
    rail_serial base;
    struct sp_port *port;
} sp_serial;

static unsigned to_ms(double s)
{
    if (!(s > 0.0))
        return 1;
    if (s > 3600.0)
        s = 3600.0;
    return (unsigned)ceil(s * 1000.0);
}

static void sp_reason(char *why, size_t why_len, const char *what)
{
    char *m = sp_last_error_message();
    snprintf(why, why_len, "%s: %s", what, m ? m : "unknown error");
    if (m)
        sp_free_error_message(m);
}

static rail_err sp_write_fn(rail_serial *s, const void *buf, size_t n, double timeout_s)
{
    sp_serial *p = (sp_serial *)s;
    int r = sp_blocking_write(p->port, buf, n, to_ms(timeout_s));
    if (r < 0) {
        sp_reason(s->why, sizeof s->why, "write failed");
        return RAIL_E_DISCONNECTED;
    }
    if ((size_t)r < n) {
        snprintf(s->why, sizeof s->why, "write timed out after %d of %zu bytes", r, n);
        return RAIL_E_TIMEOUT;
    }
    return RAIL_OK;
}

static rail_err sp_read_fn(rail_serial *s, void *buf, size_t n, size_t *got, double timeout_s)
{
    sp_serial *p = (sp_serial *)s;
    *got = 0;
    int r = sp_blocking_read_next(p->port, buf, n, to_ms(timeout_s));
    if (r < 0) {
        sp_reason(s->why, sizeof s->why, "read failed");
        return RAIL_E_DISCONNECTED;
    }
    *got = (size_t)r;
    return RAIL_OK;
}

static void sp_close_fn(rail_serial *s)
{
    sp_serial *p = (sp_serial *)s;
    sp_close(p->port);
    sp_free_port(p->port);
    free(p);
}

static const rail_serial_ops sp_ops = {"libserialport", sp_write_fn, sp_read_fn, sp_close_fn};

rail_err rail_serial_open_sp(rail_serial **out, const char *path, int baud, char *why, size_t why_len)
{
    *out = NULL;
    struct sp_port *port = NULL;
    if (sp_get_port_by_name(path, &port) != SP_OK) {
        sp_reason(why, why_len, "port lookup failed");
        return RAIL_E_IO;
    }
    if (sp_open(port, SP_MODE_READ_WRITE) != SP_OK) {
        sp_reason(why, why_len, "open failed");
        sp_free_port(port);
        return RAIL_E_IO;
    }
    if (sp_set_baudrate(port, baud) != SP_OK || sp_set_bits(port, 8) != SP_OK ||
        sp_set_parity(port, SP_PARITY_NONE) != SP_OK || sp_set_stopbits(port, 1) != SP_OK ||
        sp_set_flowcontrol(port, SP_FLOWCONTROL_NONE) != SP_OK) {
        sp_reason(why, why_len, "configuring 8N1 failed");
        sp_close(port);
        sp_free_port(port);
        return RAIL_E_IO;
    }
    sp_serial *p = calloc(1, sizeof *p);
    if (!p) {
        sp_close(port);
        sp_free_port(port);
        snprintf(why, why_len, "out of memory");
        return RAIL_E_NOMEM;
    }
    p->base.ops = &sp_ops;
    rail_text_copy(p->base.path, sizeof p->base.path, path);
    p->port = port;
    *out = &p->base;
    return RAIL_OK;
}

rail_err rail_serial_list(rail_serial_port_info *ports, size_t max, size_t *count, char *why,
                          size_t why_len)
{
    *count = 0;
    struct sp_port **list = NULL;
    if (sp_list_ports(&list) != SP_OK) {
        sp_reason(why, why_len, "listing serial ports failed");
        return RAIL_E_IO;
    }
    for (size_t i = 0; list[i] && i < 4096; i++) {
        if (*count >= max)
            break;
        rail_serial_port_info *o = &ports[*count];
        memset(o, 0, sizeof *o);
        const char *name = sp_get_port_name(list[i]);
        const char *desc = sp_get_port_description(list[i]);
        rail_text_copy(o->path, sizeof o->path, name ? name : "");
        rail_text_copy(o->description, sizeof o->description, desc ? desc : "");
        o->usb_vid = o->usb_pid = -1;
        enum sp_transport t = sp_get_port_transport(list[i]);
        rail_text_copy(o->transport, sizeof o->transport,
                       t == SP_TRANSPORT_USB ? "usb" : t == SP_TRANSPORT_BLUETOOTH ? "bluetooth" : "native");
        if (t == SP_TRANSPORT_USB) {
            int vid = -1, pid = -1;
            if (sp_get_port_usb_vid_pid(list[i], &vid, &pid) == SP_OK) {
                o->usb_vid = vid;
                o->usb_pid = pid;
            }
            const char *sn = sp_get_port_usb_serial(list[i]);
            rail_text_copy(o->serial, sizeof o->serial, sn ? sn : "");
        }
        (*count)++;
    }
    sp_free_port_list(list);
    return RAIL_OK;
}
