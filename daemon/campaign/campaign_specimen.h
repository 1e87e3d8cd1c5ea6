/* campaign_specimen.h: a specimen record as the API shows and takes it, and what a trial of it
 * changes in the rig file (campaign_specimen.c). */
#ifndef RIBBON_CAMPAIGN_SPECIMEN_H
#define RIBBON_CAMPAIGN_SPECIMEN_H

#include <jansson.h>
#include <stddef.h>

#include "store.h"

#define CAMPAIGN_MAX_OVERRIDES 16

/* The specimen's keys of a trial's rig file, "section.key=value" (ptr[k] -> text[k]). */
typedef struct campaign_overrides {
    char text[CAMPAIGN_MAX_OVERRIDES][96];
    const char *ptr[CAMPAIGN_MAX_OVERRIDES];
    int n;
} campaign_overrides;

/* The record as JSON: every field, null for what is unknown, state as text; its calibration and
 * the last refit's failure as the objects stored (null when none). */
json_t *campaign_specimen_json(const store_specimen *sp);
/* A new specimen from POST /specimens's body: name (letters, digits, '.', '_', '-'; at most 63),
 * phi_deg in (0, 180), gamma in (0, 0.5) required; the size, material, modulus and density
 * default to defaults' (the rig file's scene); measured crease angles (0..180), positions (0..1,
 * left < right), folded_at (ISO 8601 with a zone), crease_orientation ("up", "down") optional.
 * An unknown field, a wrong type or a value out of range is -1 with the field named. */
int campaign_specimen_from_json(const json_t *body, const store_specimen *defaults, store_specimen *out, char *why,
                                size_t why_len);
/* Is name a specimen a trial may use? 0 and *out, or -1 naming why not: -2 when unknown (the
 * caller's 404 or 400), -1 when retired or broken (a 409). */
int campaign_specimen_usable(store *st, const char *name, store_specimen *out, char *why, size_t why_len);
/* The rig-file keys of a trial of sp: its label, material, size, design (folds.angle_deg with
 * scene_sign's sign, +1 or -1; folds.position) and the measured creases it has. */
int campaign_specimen_overrides(const store_specimen *sp, int scene_sign, campaign_overrides *ov, char *why,
                                size_t why_len);
/* The measured fields of body (crease angles in (0, 180), positions in (0, 1) with left < right,
 * folded_at ISO 8601 with a zone) into sp; absent fields leave sp's. -1 naming the field. Shared
 * with an operator step's confirmation (campaign_operator.c). */
int campaign_specimen_measured_from_json(const json_t *body, store_specimen *sp, char *why, size_t why_len);
/* A specimen name in the API's path grammar (letters, digits, '.', '_', '-'; 1..63 bytes)? */
int campaign_specimen_name_ok(const char *name, char *why, size_t why_len);

#endif
