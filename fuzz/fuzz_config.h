/* fuzz_config.h: what the fuzz targets that load configuration (a scene directly, a rig file, or
 * either with overrides) share: the checks of an accepted result and the shipped texts they start
 * from. */
#ifndef RIBBON_FUZZ_CONFIG_H
#define RIBBON_FUZZ_CONFIG_H

#include <stddef.h>

#include "scene.h"

/* abort()s (fuzz_fail) unless every double of s is finite and rod_scene_check accepts it. */
void fuzz_check_scene(const char *who, const rod_scene *s);

/* Load text as a rig file (relative paths from the shipped config/ folder) with n overrides and
 * check the outcome: a refusal has a reason, an accepted rig a valid scene and finite settings. */
void fuzz_rig_text(const char *who, const char *text, size_t len, const char *const *ovr, int n);

/* The text of a shipped file under RIBBON_SOURCE_DIR (e.g. "config/mock.ini"), read once and
 * kept for the process (a fuzz run's fixture, not state of the code under test); aborts if it
 * cannot be read. */
const char *fuzz_shipped_text(const char *rel, size_t *len);

#endif
