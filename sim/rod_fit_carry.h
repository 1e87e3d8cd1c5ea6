/* rod_fit_carry.h: a later fit carrying what an earlier one learned about the crease positions
 * (issue 32 A/B/D). The trial's fit 0 takes the tracked centrelines, which determine where the
 * creases are; its refreshes (the fit with the shear) leave the centrelines out, and the shear's
 * frames alone do not pin the positions. So a refresh takes fit 0's positions and their standard
 * errors as its prior on them: a sequential update on the positions only; the angles, the hinge
 * and E keep their priors on the specimen's values and are left to the frames. Owned here, below
 * the trial and ribbon-fit-family, so that both refresh by this one rule. */
#ifndef RIBBON_SIM_ROD_FIT_CARRY_H
#define RIBBON_SIM_ROD_FIT_CARRY_H

#include "rod_fit.h"

/* The carried prior's floor, over l: the traced centreline's largest measured error, at the point
 * past each crease (the tracer cuts the crease's corner: 0.001 l at most on the mock trial's sharp
 * creases, docs/calibration.md "The traced points, not the smooth curve"). That error is a bias,
 * the same in every frame, which fit 0's standard errors (independent noise and a common mode per
 * centreline) do not hold, so a carried prior is never narrower. */
#define ROD_FIT_CARRY_FLOOR 0.001

/* The prior width a refresh gives a position fit 0 found with standard error se: se, at least
 * floor and at most cap (the specimen's tolerance; also where se is not finite: not determined). */
double rod_fit_carry_sigma(double se, double floor, double cap);

/* The refresh after fit 0. sc: in, the specimen's strip (the one fit 0 was given); out, fit 0's
 * strip (u0, fit 0's values in fit units, put in: the model is evaluated and started there, where
 * the frames fit 0 saw have their state). o: both crease positions fitted where the strip has them,
 * with priors of rod_fit_carry_sigma(se0[k], floor, cap) around fit 0's values; every other prior
 * stays centred on the specimen's values (centre, the caller's storage for ROD_FIT_NKEYS values,
 * becomes o->prior_centre: keep it alive through the fit), and the bounds left at their defaults
 * are the ones around the specimen's values (fit 0's). Returns 1; 0 (nothing touched) when fit 0's
 * positions are not finite. */
int rod_fit_carry_positions(const double u0[ROD_FIT_NKEYS], const double se0[ROD_FIT_NKEYS], double floor,
                            double cap, rod_scene *sc, rod_fit_opts *o, double centre[ROD_FIT_NKEYS]);

#endif
