/* campaign_operator.c: an operator step ("mount S-12, phi 90, Gamma 0.17, measured angles?") asks
 * for a form's fields and holds the queue until someone confirms it with their values. The values
 * are measurements of the step's specimen, so they are checked as the specimen's own are (a value
 * that cannot be a clamped folded strip is refused, naming the field) and, once confirmed, become
 * the specimen's record, which the next trial of it then uses. */
#include "campaign_operator.h"

#include <stdio.h>
#include <string.h>

#include "campaign_specimen.h"

static const char *const form_fields[] = {"crease_angle_left_deg", "crease_angle_right_deg", "crease_position_left",
                                          "crease_position_right", "folded_at"};
#define N_FORM (sizeof form_fields / sizeof form_fields[0])

static int known(const char *f)
{
    for (size_t i = 0; i < N_FORM; i++)
        if (!strcmp(f, form_fields[i])) return 1;
    return 0;
}

int campaign_operator_fields_check(const json_t *fields, int has_specimen, char *why, size_t why_len)
{
    if (!json_is_array(fields)) {
        snprintf(why, why_len, "field \"fields\" must be an array of field names");
        return -1;
    }
    size_t n = json_array_size(fields);
    for (size_t i = 0; i < n; i++) {
        json_t *f = json_array_get(fields, i);
        if (!json_is_string(f) || !known(json_string_value(f))) {
            snprintf(why, why_len, "fields[%zu] is not a field an operator step can ask for (crease_angle_left_deg, "
                     "crease_angle_right_deg, crease_position_left, crease_position_right, folded_at)", i);
            return -1;
        }
        for (size_t j = 0; j < i; j++)
            if (json_equal(f, json_array_get(fields, j))) {
                snprintf(why, why_len, "fields[%zu] \"%s\" is asked twice", i, json_string_value(f));
                return -1;
            }
    }
    if (n && !has_specimen) {
        snprintf(why, why_len, "an operator step with fields names the specimen they measure (\"specimen\")");
        return -1;
    }
    return 0;
}

int campaign_operator_values_check(const store_queue_item *step, const json_t *values, store_specimen *sp,
                                   char *why, size_t why_len)
{
    if (!json_is_object(values)) {
        snprintf(why, why_len, "field \"values\" must be an object of the step's fields");
        return -1;
    }
    json_error_t je;
    json_t *fields = json_loads(step->fields_json[0] ? step->fields_json : "[]", 0, &je);
    if (!fields) {
        snprintf(why, why_len, "queue item %lld: its stored fields are not JSON: %s", (long long)step->id, je.text);
        return -1;
    }
    int rc = 0;
    size_t n = json_array_size(fields);
    for (size_t i = 0; i < n && !rc; i++) {
        const char *f = json_string_value(json_array_get(fields, i));
        json_t *v = json_object_get(values, f ? f : "");
        if (!v || json_is_null(v)) {
            snprintf(why, why_len, "the step asks for \"%s\": values has none", f ? f : "?");
            rc = -1;
        }
    }
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)values, k, v)
    {
        if (rc) break;
        int asked = 0;
        for (size_t i = 0; i < n; i++)
            if (!strcmp(k, json_string_value(json_array_get(fields, i)))) asked = 1;
        if (!asked) {
            snprintf(why, why_len, "\"%.64s\" is not a field of this step", k);
            rc = -1;
        }
    }
    json_decref(fields);
    if (rc) return -1;
    store_specimen next = *sp;
    if (campaign_specimen_measured_from_json(values, &next, why, why_len)) return -1;
    *sp = next;
    return 0;
}
