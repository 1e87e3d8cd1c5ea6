/*
 * plot_regime.c: the snap-regime names the plots understand.
 *
 * The simulator and the store write regimes as text ("asymmetric", "symmetric", "none" for a
 * prediction without a snap, "no snap" from the bench); the phase diagram needs them as codes.
 * Anything unrecognised is "unknown", which the figures still draw (in their own style) rather
 * than dropping the trial.
 */
#include "plot.h"

#include <strings.h>

plot_regime plot_regime_parse(const char *s)
{
    if (!s)
        return PLOT_REGIME_UNKNOWN;
    if (strcasecmp(s, "asymmetric") == 0)
        return PLOT_REGIME_ASYMMETRIC;
    if (strcasecmp(s, "symmetric") == 0)
        return PLOT_REGIME_SYMMETRIC;
    if (strcasecmp(s, "none") == 0 || strcasecmp(s, "no snap") == 0 || strcasecmp(s, "no-snap") == 0 ||
        strcasecmp(s, "no_snap") == 0)
        return PLOT_REGIME_NO_SNAP;
    if (strcasecmp(s, "no-upper") == 0)
        return PLOT_REGIME_NO_UPPER;
    return PLOT_REGIME_UNKNOWN;
}

const char *plot_regime_name(plot_regime r)
{
    switch (r) {
    case PLOT_REGIME_ASYMMETRIC: return "asymmetric";
    case PLOT_REGIME_SYMMETRIC: return "symmetric";
    case PLOT_REGIME_NO_SNAP: return "no snap";
    case PLOT_REGIME_NO_UPPER: return "no-upper";
    case PLOT_REGIME_UNKNOWN: break;
    }
    return "unknown";
}
