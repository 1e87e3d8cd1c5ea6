/* scene_write.h: a rod_scene written back as a scene file that the loader reads to the same
 * values, driven by the loader's own key table (config/scene_file.h), so every key is written
 * and none is invented. Used by `ribbon-sim fit --out-scene` and `ribbonctl calibrate
 * --write-scene`; it lives beside the loader so every front end can write what the loader reads. */
#ifndef RIBBON_CONFIG_SCENE_WRITE_H
#define RIBBON_CONFIG_SCENE_WRITE_H

#include <stdio.h>

#include "scene.h"

/* Writes sc to f, after the comment lines in header (each line prefixed "; "; NULL for none).
 * Per-crease keys that are unset (NaN) are left out, and folds.stiffness_factor beside compliant
 * hinges (the loader refuses it there). Returns 0, or -1 on a write error. */
int cfg_scene_write(FILE *f, const rod_scene *sc, const char *header);

#endif
