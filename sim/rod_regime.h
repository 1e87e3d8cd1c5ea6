/* rod_regime.h: the rule that reads a snap's pathway (symmetric or asymmetric) from the peak |A|
 * of the snap, owned here so that the simulator's classification (rod_protocol.c, on its own A)
 * and the trial's snap detector (daemon/trial/snap_detect.c, on the tracked frames) apply the
 * same rule and the predicted and measured regimes are the same quantity.
 *
 * Why a threshold of 0.5 rad (derivation and table: docs/simulator.md "Snap, and the regime
 * rule"). The pathway the twin really took is defined without any threshold on A: how the peak
 * |A| of the snap scales with the crease difference rel. On the symmetric pathway A is the
 * linear response to the imperfection (halving rel halves the peak: exponent
 * d ln(peak) / d ln(rel) = 1); on the asymmetric one the antisymmetric mode grows by itself and
 * the peak hardly depends on rel (exponent near 0). Over the paper, mock and PET scenes at
 * N = 61, Gamma 0.13 .. 0.23 and rel 1e-6 .. 5%: every snap with exponent >= 0.8 peaks at
 * |A| <= 0.378 rad, every one with exponent <= 0.35 at |A| >= 0.72 rad; 0.5 is near their
 * geometric mean, and the tracker's noise on A (0.015 rad RMS per frame) cannot cross it (its
 * largest excursion over a snap's frames is about 0.06). The old 0.05 rad was crossed by a 3%
 * crease difference at Gamma 0.21 (peak 0.052 on the mock scene, 0.077 on the paper's). */
#ifndef RIBBON_SIM_ROD_REGIME_H
#define RIBBON_SIM_ROD_REGIME_H

/* rad: the default of the scene key snap.asym_threshold. */
#define ROD_REGIME_ASYM_THRESHOLD 0.5

/* 1 when a snap whose peak |A| from its onset to its end is peak_abs_a (rad) took the
 * asymmetric pathway under threshold (rad, snap.asym_threshold); 0 otherwise, and for a
 * non-finite peak (never a pathway read from nothing). */
int rod_regime_asymmetric(double peak_abs_a, double threshold);

#endif
