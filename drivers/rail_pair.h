/* rail_pair.h: the rig's two rails watched together: "any fault stops both rails"
 * (DESIGN.md section 6). rail_pair_poll() reads both rails (rate limited, as rail_status_get)
 * and, if either is in alarm, fault or disconnected, emergency-stops the other and returns an
 * error naming the rail and the reason. The trial runner calls it from its loop instead of
 * polling the rails one by one. */
#ifndef RIBBON_DRIVERS_RAIL_PAIR_H
#define RIBBON_DRIVERS_RAIL_PAIR_H

#include <stddef.h>

#include "rail.h"

/* Poll both; on a fault of either, estop the other. why gets "rail NAME: reason" on failure.
 * Returns RAIL_OK when both are healthy (idle, moving or homing). */
rail_err rail_pair_poll(rail *compress, rail *shear, rail_status *st_compress, rail_status *st_shear,
                        char *why, size_t why_len);
/* One rail's reading (rail_status_get's return and status) judged as rail_pair_poll judges it:
 * RAIL_OK when healthy (idle, moving or homing), else the fault with why = "rail NAME: reason".
 * For callers that poll the rails one at a time so a fault is known after one round trip (the
 * live trial's poller); they must then stop the other rail themselves. */
rail_err rail_pair_judge(rail *r, rail_err e, const rail_status *st, char *why, size_t why_len);
/* Emergency-stop both (both are always attempted); the first error is returned. */
rail_err rail_pair_estop(rail *compress, rail *shear);

#endif
