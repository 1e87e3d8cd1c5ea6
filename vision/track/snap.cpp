// snap.cpp: locating the snap-through in a Delta Z time series.
//
// A snap is the one big jump of a trial: the ribbon leaves its upper state within a frame or two.
// The first frame whose change from the previous measured frame exceeds both an absolute floor
// (`min_jump`, normalised Delta Z) and a fraction of the series' whole range is that frame. Frames
// without a measurement are skipped, so a lost frame cannot fake or hide a jump.
#include "vis_internal.hpp"
#include "vis_track.h"

extern "C" int vis_snap_find(const double *dz, const unsigned char *valid, size_t n, double min_jump,
                             double fraction)
{
    if (!dz || n < 2 || n > (size_t)1 << 30)
        return -1;
    double lo = 0, hi = 0;
    bool any = false;
    for (size_t i = 0; i < n; i++) {
        if ((valid && !valid[i]) || !std::isfinite(dz[i]))
            continue;
        lo = any ? std::min(lo, dz[i]) : dz[i];
        hi = any ? std::max(hi, dz[i]) : dz[i];
        any = true;
    }
    if (!any)
        return -1;
    const double thr = std::max(min_jump, fraction * (hi - lo));
    long last = -1;
    for (size_t i = 0; i < n; i++) {
        if ((valid && !valid[i]) || !std::isfinite(dz[i]))
            continue;
        if (last >= 0 && std::fabs(dz[i] - dz[last]) > thr)
            return (int)i;
        last = (long)i;
    }
    return -1;
}
