/* rail_open.c: which driver a spec names, opened (see rail_open.h). The only place that knows
 * every driver; the drivers themselves know nothing of each other or of config files. */
#include "rail_open.h"

#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "grbl_link.h"

rail_err rail_open(const rail_open_spec *c, rail_clock clock, grbl_link *shared, rail **out,
                   char *why, size_t why_len)
{
    *out = NULL;
    if (!strcmp(c->driver, "mock"))
        return rail_mock_open(out, &c->params, &c->mock, clock, why, why_len);
    if (!strcmp(c->driver, "gcode"))
        return rail_gcode_open(out, &c->params, &c->gcode, shared, clock, why, why_len);
    if (!strcmp(c->driver, "modbus"))
        return rail_modbus_open(out, &c->params, &c->modbus, clock, why, why_len);
    snprintf(why, why_len, "rail %s: unknown driver '%s'", c->params.name, c->driver);
    return RAIL_E_INVALID;
}

rail_err rail_open_pair(const rail_open_spec *cc, const rail_open_spec *cs, rail_clock clock,
                        rail **compress, rail **shear, char *why, size_t why_len)
{
    *compress = *shear = NULL;
    grbl_link *link = NULL;
    bool share = !strcmp(cc->driver, "gcode") && !strcmp(cs->driver, "gcode") &&
                 !strcmp(cc->gcode.port, cs->gcode.port);
    if (share) {
        if (cc->gcode.axis == cs->gcode.axis) {
            snprintf(why, why_len, "both rails are axis %c of controller %s", cc->gcode.axis, cc->gcode.port);
            return RAIL_E_INVALID;
        }
        rail_err e = grbl_link_open(&link, &cc->gcode, clock, why, why_len);
        if (e != RAIL_OK)
            return e;
    }
    rail_err e = rail_open(cc, clock, link, compress, why, why_len);
    if (e == RAIL_OK)
        e = rail_open(cs, clock, link, shear, why, why_len);
    grbl_link_release(link); /* the rails hold their own references */
    if (e != RAIL_OK) {
        rail_close(*compress);
        *compress = NULL;
    }
    return e;
}
