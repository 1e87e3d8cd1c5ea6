/* rail_pair.c: fault propagation between the two rails (see rail_pair.h). A rail is unhealthy
 * when its reading failed or its state is alarm, fault or disconnected; the other rail then gets
 * rail_estop() at once, before the caller sees the error, so no code path can forget it. */
#include "rail_pair.h"

#include <stdbool.h>
#include <stdio.h>

static bool healthy(rail_err e, const rail_status *st)
{
    return e == RAIL_OK && (st->state == RAIL_STATE_IDLE || st->state == RAIL_STATE_MOVING ||
                            st->state == RAIL_STATE_HOMING);
}

static rail_err fault_of(rail *r, rail_err e, const rail_status *st, char *why, size_t why_len)
{
    const char *name = rail_get_params(r)->name;
    if (e != RAIL_OK)
        snprintf(why, why_len, "%s", rail_last_error(r));
    else
        snprintf(why, why_len, "rail %s: %s%s%s", name, rail_state_name(st->state), st->message[0] ? ": " : "",
                 st->message);
    if (e != RAIL_OK)
        return e;
    return st->state == RAIL_STATE_DISCONNECTED ? RAIL_E_DISCONNECTED
           : st->state == RAIL_STATE_ALARM      ? RAIL_E_DEVICE
                                                : RAIL_E_STATE;
}

rail_err rail_pair_poll(rail *a, rail *b, rail_status *sa, rail_status *sb, char *why, size_t why_len)
{
    rail_err ea = rail_status_get(a, sa);
    rail_err eb = rail_status_get(b, sb);
    bool ha = healthy(ea, sa), hb = healthy(eb, sb);
    if (ha && hb)
        return RAIL_OK;
    /* Stop whatever is still healthy first, then report. */
    if (ha)
        rail_estop(a);
    if (hb)
        rail_estop(b);
    return !ha ? fault_of(a, ea, sa, why, why_len) : fault_of(b, eb, sb, why, why_len);
}

rail_err rail_pair_judge(rail *r, rail_err e, const rail_status *st, char *why, size_t why_len)
{
    return healthy(e, st) ? RAIL_OK : fault_of(r, e, st, why, why_len);
}

rail_err rail_pair_estop(rail *a, rail *b)
{
    rail_err ea = rail_estop(a);
    rail_err eb = rail_estop(b);
    return ea != RAIL_OK ? ea : eb;
}
