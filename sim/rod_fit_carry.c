/* rod_fit_carry.c: a refresh's prior on the crease positions from fit 0's (rod_fit_carry.h). */
#include "rod_fit_carry.h"

#include <math.h>

double rod_fit_carry_sigma(double se, double floor, double cap)
{
    if (!(se < INFINITY)) return cap; /* not determined (or NaN): the tolerance */
    return fmin(fmax(se, floor), cap);
}

int rod_fit_carry_positions(const double u0[ROD_FIT_NKEYS], const double se0[ROD_FIT_NKEYS], double floor,
                            double cap, rod_scene *sc, rod_fit_opts *o, double centre[ROD_FIT_NKEYS])
{
    const rod_fit_key pos[2] = {ROD_FIT_POSITION_LEFT, ROD_FIT_POSITION_RIGHT};
    if (!isfinite(u0[pos[0]]) || !isfinite(u0[pos[1]])) return 0;
    rod_fit_scene_values(sc, centre); /* the specimen's */
    char unused[200];
    for (int i = 0; i < 2; i++)
        if (!rod_fit_key_usable(sc, pos[i], unused, sizeof unused)) {
            o->fit[pos[i]] = 1;
            o->prior_sigma[pos[i]] = rod_fit_carry_sigma(se0[pos[i]], floor, cap);
        }
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (o->fit[k] && (isnan(o->lo[k]) || isnan(o->hi[k]))) {
            double lo, hi;
            rod_fit_key_bounds((rod_fit_key)k, centre[k], &lo, &hi);
            if (isnan(o->lo[k])) o->lo[k] = lo;
            if (isnan(o->hi[k])) o->hi[k] = hi;
        }
    for (int i = 0; i < 2; i++) centre[pos[i]] = u0[pos[i]];
    double u[ROD_FIT_NKEYS];
    for (int k = 0; k < ROD_FIT_NKEYS; k++) u[k] = isfinite(u0[k]) ? u0[k] : centre[k];
    rod_fit_scene_apply(sc, u);
    o->prior_centre = centre;
    return 1;
}
