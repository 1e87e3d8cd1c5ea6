/* campaign_operator.h: an operator step's form: the fields it asks for, and the check of the
 * values it is confirmed with (campaign_operator.c). */
#ifndef RIBBON_CAMPAIGN_OPERATOR_H
#define RIBBON_CAMPAIGN_OPERATOR_H

#include <jansson.h>
#include <stddef.h>

#include "store.h"

/* fields: a JSON array of distinct names from the form's fields (crease_angle_left_deg,
 * crease_angle_right_deg, crease_position_left, crease_position_right, folded_at); a form with
 * fields needs a specimen (has_specimen) to write them to. 0, or -1 naming what is wrong. */
int campaign_operator_fields_check(const json_t *fields, int has_specimen, char *why, size_t why_len);
/* The values of a confirmation: an object with exactly the step's fields, each a possible value
 * (angles that can be clamped: in (0, 180) deg; positions in (0, 1), left < right; a date-time
 * with a zone). On success *sp (the step's specimen, as stored) carries the new measurements and
 * 0 is returned; -1 with the field named otherwise (nothing changed). */
int campaign_operator_values_check(const store_queue_item *step, const json_t *values, store_specimen *sp,
                                   char *why, size_t why_len);

#endif
