/* rod_twin.h: the simulated ribbon of mock mode, driven by the rails instead of by a protocol.
 *
 * A digital twin is a rod that starts in its upper state at the mounting compression and is then
 * moved by whatever the clamps do: each rod_twin_advance() integrates the dynamics (implicit Euler,
 * the scene's dt as the largest step) from the twin's time to t_to while the clamp placement goes
 * linearly from where it was to the (Delta L, Delta W) given, which the caller computes from the
 * rails' positions. So the twin snaps when, and because, the rails shear it, and whatever the
 * runner does (hold, stop, abort, return) is what the ribbon feels. */
#ifndef RIBBON_SIM_ROD_TWIN_H
#define RIBBON_SIM_ROD_TWIN_H

#include "rod.h"
#include "rod_observe.h"
#include "rod_snap_watch.h"

typedef struct rod_twin rod_twin;

/* Builds the rod of sc and brings it to the upper state at Delta L = dl_start (the documented
 * route, rod_route.h), Delta W = 0, at rest, at time 0. */
rod_status rod_twin_open(const rod_scene *sc, double dl_start, rod_twin **out, char *why, size_t why_len);
void rod_twin_close(rod_twin *tw);

/* Integrates to time t_to (> current time; equal is a no-op) with the clamps moving linearly to
 * (dl, dw). Failed steps are halved down to dt / 1024; then the status and err say where. */
rod_status rod_twin_advance(rod_twin *tw, double t_to, double dl, double dw, char *why, size_t why_len);

double rod_twin_time(const rod_twin *tw);
/* The clamps' Delta W of the current state. */
double rod_twin_dw(const rod_twin *tw);
/* Delta Z, A, ... of the current state (rod_observe.h). */
void rod_twin_observe(rod_twin *tw, rod_obs *o);
/* The current state, for rendering. */
const rod *rod_twin_rod(const rod_twin *tw);
/* N: the shear force the clamps hold the rod with, along +Delta W, at the last accepted state:
 * the generalised force conjugate to the rail's shear displacement x = Delta W l, i.e. dE/dx
 * summed over the prescribed DOFs (each clamp moves by x / 2, in opposite directions,
 * rod_set_clamps). It is what a force sensor in series with a position-controlled shear rail
 * reads (the rod's elastic reaction; the clamps' own inertia excluded), and it drops at the snap. */
double rod_twin_shear_force(const rod_twin *tw);
/* The twin's own snap so far (rod_snap_watch.h), from every accepted step since the open: its
 * onset Delta W, the peak |A| and the pathway, with the scene's snap.speed and
 * snap.asym_threshold and 2 s of pathway (the prediction's post_snap_time). The truth a trial's
 * measurement is scored against. */
void rod_twin_snap(const rod_twin *tw, rod_snap_report *out);
/* Kinetic energy (J) of the last step and the total count of Newton failures recovered by halving. */
double rod_twin_kinetic(const rod_twin *tw);
long rod_twin_halvings(const rod_twin *tw);

#endif
