/* rail_modbus_link.c: a connected libmodbus context for a drive (see rail_modbus_link.h).
 * Error recovery is off: the driver maps every failure itself (rail_modbus.c, mb_fail). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rail_modbus_link.h"
#include "rail_serial.h"

static rail_err parse_host_port(const char *a, char *host, size_t hn, int *port)
{
    const char *c = strrchr(a, ':');
    if (!c || c == a || (size_t)(c - a) >= hn)
        return RAIL_E_INVALID;
    memcpy(host, a, (size_t)(c - a));
    host[c - a] = 0;
    char *end = NULL;
    long p = strtol(c + 1, &end, 10);
    if (!*(c + 1) || *end || p < 1 || p > 65535)
        return RAIL_E_INVALID;
    *port = (int)p;
    return RAIL_OK;
}

rail_err rail_modbus_link_open(modbus_t **out, const char *address, int rtu, int baud, char parity, int slave,
                               double timeout_s, char *why, size_t why_len)
{
    *out = NULL;
    modbus_t *ctx = NULL;
    if (rtu) {
        char par = parity;
        if (par != 'N' && par != 'E' && par != 'O') {
            snprintf(why, why_len, "modbus: parity must be N, E or O");
            return RAIL_E_INVALID;
        }
        /* The line may be named like a G-code port: a path or usb:VID:PID[:SERIAL]. */
        char dev[256];
        rail_err re = rail_serial_resolve(address, dev, sizeof dev, why, why_len);
        if (re != RAIL_OK)
            return re;
        ctx = modbus_new_rtu(dev, baud, par, 8, par == 'N' ? 2 : 1);
    } else {
        char host[128];
        int port = 0;
        if (parse_host_port(address, host, sizeof host, &port) != RAIL_OK) {
            snprintf(why, why_len, "modbus: address '%.100s' is not HOST:PORT", address);
            return RAIL_E_INVALID;
        }
        ctx = modbus_new_tcp(host, port);
    }
    if (!ctx) {
        snprintf(why, why_len, "modbus: cannot create a context for %.100s: %s", address,
                 modbus_strerror(errno));
        return RAIL_E_INVALID;
    }
    modbus_set_slave(ctx, slave);
    uint32_t sec = (uint32_t)timeout_s, usec = (uint32_t)((timeout_s - sec) * 1e6);
    modbus_set_response_timeout(ctx, sec, usec);
    modbus_set_byte_timeout(ctx, sec, usec);
    modbus_set_error_recovery(ctx, MODBUS_ERROR_RECOVERY_NONE);
    if (modbus_connect(ctx) != 0) {
        snprintf(why, why_len, "modbus: cannot connect to %.100s: %s", address, modbus_strerror(errno));
        modbus_free(ctx);
        return RAIL_E_IO;
    }
    *out = ctx;
    return RAIL_OK;
}

void rail_modbus_link_close(modbus_t *ctx)
{
    if (ctx) {
        modbus_close(ctx);
        modbus_free(ctx);
    }
}
