/* rail_serial_stream.c: the calls through a serial handle's vtable (rail_serial_stream.h). */
#include "rail_serial_stream.h"

rail_err rail_serial_write(rail_serial *s, const void *buf, size_t n, double timeout_s)
{
    return s->ops->write(s, buf, n, timeout_s);
}

rail_err rail_serial_read(rail_serial *s, void *buf, size_t n, size_t *got, double timeout_s)
{
    return s->ops->read(s, buf, n, got, timeout_s);
}

void rail_serial_close(rail_serial *s)
{
    if (s)
        s->ops->close(s);
}

const char *rail_serial_kind(const rail_serial *s)
{
    return s->ops->name;
}
