/* trial_config_text.h: the trial's config text (trial_config_text.c). */
#ifndef RIBBON_TRIAL_CONFIG_TEXT_H
#define RIBBON_TRIAL_CONFIG_TEXT_H

#include "rig_config.h"

/* "# rig file PATH" + its text + "# scene file PATH" + its text (+ "# note: ..."), malloc'ed;
 * NULL when out of memory (a file that cannot be read is noted in the text instead). */
char *trial_config_text(const rig_config *cfg, const char *note);

#endif
