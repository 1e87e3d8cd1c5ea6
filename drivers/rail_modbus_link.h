/* rail_modbus_link.h: a libmodbus context for a drive's address (TCP HOST:PORT, or RTU on a
 * serial line named by path or usb:VID:PID[:SERIAL]), with the slave id and timeouts set and
 * connected. Shared by the driver (rail_modbus.c) and the read-only probe (rail_modbus_probe.c),
 * so both reach a drive the same way. */
#ifndef RIBBON_DRIVERS_RAIL_MODBUS_LINK_H
#define RIBBON_DRIVERS_RAIL_MODBUS_LINK_H

#include <modbus.h>
#include <stddef.h>

#include "rail.h"

/* Create and connect: address TCP "HOST:PORT" or (rtu) a serial line, baud and parity 'N' 'E' 'O'
 * for RTU, slave 1..247, timeout_s per request and per byte (the fields of rail_modbus_params,
 * passed one by one so this file stays below rail_modbus.h). On failure *out is NULL and why says what (RAIL_E_INVALID for a bad
 * address or parity, RAIL_E_IO when the drive cannot be reached). */
rail_err rail_modbus_link_open(modbus_t **out, const char *address, int rtu, int baud, char parity, int slave,
                               double timeout_s, char *why, size_t why_len);
/* Close and free (NULL is fine). */
void rail_modbus_link_close(modbus_t *ctx);

#endif
