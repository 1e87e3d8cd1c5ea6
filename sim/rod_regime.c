/* rod_regime.c: the pathway rule (see rod_regime.h for its derivation). */
#include "rod_regime.h"

#include <math.h>

int rod_regime_asymmetric(double peak_abs_a, double threshold)
{
    if (!isfinite(peak_abs_a) || !isfinite(threshold)) return 0;
    return fabs(peak_abs_a) > threshold;
}
