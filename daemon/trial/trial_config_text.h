/* trial_config_text.h: the trial's config text (trial_config_text.c), written and read back. */
#ifndef RIBBON_TRIAL_CONFIG_TEXT_H
#define RIBBON_TRIAL_CONFIG_TEXT_H

#include "rig_config.h"

/* "# rig file PATH" + its text + "# scene file PATH" + its text (+ "# note: ..."), malloc'ed;
 * NULL when out of memory (a file that cannot be read is noted in the text instead). */
char *trial_config_text(const rig_config *cfg, const char *note);

/* The scene file's text inside a stored config text (the reverse of the above, for re-using a
 * stored trial's scene: ribbonctl calibrate): *begin and *len delimit it in text, from the line
 * after "# scene file PATH" to the trailing "# note: ..." or "# replay of trial N" line (a
 * replay's row appends that to its source's text) or the end. Returns 0, or -1 when text has no
 * scene file, or says it could not be read. */
int trial_config_text_scene(const char *text, const char **begin, size_t *len);

#endif
