/* trial_config_text.h: the trial's config text (trial_config_text.c), written and read back. */
#ifndef RIBBON_TRIAL_CONFIG_TEXT_H
#define RIBBON_TRIAL_CONFIG_TEXT_H

#include <jansson.h>

#include "rig_config.h"
#include "store.h"

/* "# rig file PATH" + its text + "# scene file PATH" + its text + "# overrides applied in order
 * after the files: [...]" (the n_sets overrides "section.key=value" cfg was loaded with, as one
 * line of JSON, "[]" for none; no such line when sets is NULL: not known) (+ "# note: ..."), malloc'ed; NULL when out of memory (a file that
 * cannot be read is noted in the text instead). */
char *trial_config_text(const rig_config *cfg, const char *const *sets, int n_sets, const char *note);

/* The scene file's text inside a stored config text (the reverse of the above, for re-using a
 * stored trial's scene: ribbonctl calibrate): *begin and *len delimit it in text, from the line
 * after "# scene file PATH" to the trailing "# note: ..." or "# replay of trial N" line (a
 * replay's row appends that to its source's text) or the end. Returns 0, or -1 when text has no
 * scene file, or says it could not be read. */
int trial_config_text_scene(const char *text, const char **begin, size_t *len);

/* The overrides stored in text (a JSON array of strings, new reference), or NULL when the text
 * has no overrides line (a trial stored before they were) or it cannot be read. */
json_t *trial_config_text_overrides(const char *text);

/* The scene the trial ran: the stored scene file's text with the stored overrides of the scene's
 * sections applied in order, as the trial's rig_config_load did (the rig file's keys among them
 * are skipped). name names it in errors. 0, or -1 with why. */
int trial_config_text_scene_load(const char *text, const char *name, rod_scene *out, char *why, size_t why_len);

/* The in-trial fit's setup the trial ran with (rig keys sim.fit_hinge and sim.fit_keys, docs/
 * calibration.md): read from the stored rig file's [sim] section with the stored overrides of
 * those two keys applied in order, as the trial's rig_config_load did; the rig defaults (0, "")
 * where the file does not set them. For `ribbonctl calibrate`, so that a stored trial is refitted
 * with the setup its in-trial fit had (trial_calibrate_setup). 0, or -1 with why when text holds
 * no readable rig file, or the value stored is not one the rig loader accepts. */
int trial_config_text_fit(const char *text, double *fit_hinge, char *keys, size_t keys_len, char *why,
                          size_t why_len);

/* Sets "overrides" in trial (trial id's JSON, store_trial_json) to its stored overrides, or to
 * null when its config text holds none (stored before they were) or cannot be read. */
void trial_config_text_add_overrides(store *st, int64_t id, json_t *trial);

#endif
