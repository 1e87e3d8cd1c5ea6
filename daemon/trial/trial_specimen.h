/* trial_specimen.h: the specimen a rig file describes, as the store keeps it, and as the trial's
 * prediction uses it: the [specimen] measurements put into the scene (trial_specimen.c). */
#ifndef RIBBON_TRIAL_SPECIMEN_H
#define RIBBON_TRIAL_SPECIMEN_H

#include <stddef.h>

#include "rig_config.h"
#include "scene.h"
#include "store.h"

void trial_specimen_from_config(const rig_config *cfg, store_specimen *sp);

/* What the prediction of a trial uses of the specimen. */
typedef struct trial_specimen_use {
    store_creases creases; /* each crease's angle and position, where each came from, the hinge */
} trial_specimen_use;

/* The scene the trial's prediction runs on: cfg->scene with the specimen's measured creases in
 * it (the one specimen -> scene mapping; see the comment in trial_specimen.c). The result is
 * checked with rod_scene_check at the scene's node count (sim.nodes when given). Returns 0, or -1
 * with why naming the specimen key to blame (nothing is started then). */
int trial_specimen_scene(const rig_config *cfg, rod_scene *out, trial_specimen_use *use, char *why, size_t why_len);

/* s from the creases' folding (specimen.folded_at) to wall_s (s since the epoch); NaN when not
 * recorded. Returns -1 with why when folded_at lies after wall_s, else 0. */
int trial_specimen_crease_age(const rig_config *cfg, double wall_s, double *age_s, char *why, size_t why_len);

#endif
