/* campaign_specimen.c: specimens through the API (issue 35, part A): the record as JSON, a new
 * record from a request's body, whether a trial may use it, and the rig-file keys a trial of it
 * sets. A trial names its specimen; its prediction then uses the specimen's design and
 * measurements because they enter the trial's rig file as overrides (and from there the scene,
 * through trial_specimen_scene), so the trial's stored config says exactly what was used. */
#include "campaign_specimen.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cfg_datetime.h"

static json_t *num(double v) { return isfinite(v) ? json_real(v) : json_null(); }
static json_t *text(const char *s) { return s && *s ? json_string(s) : json_null(); }

json_t *campaign_specimen_json(const store_specimen *sp)
{
    json_t *o = json_object();
    json_object_set_new(o, "id", json_integer(sp->id));
    json_object_set_new(o, "name", json_string(sp->name));
    json_object_set_new(o, "state", json_string(store_specimen_state_name(sp->state) ? store_specimen_state_name(sp->state) : "new"));
    json_object_set_new(o, "state_reason", text(sp->state_reason));
    json_object_set_new(o, "state_at", text(sp->state_at));
    json_object_set_new(o, "phi_deg", num(sp->phi_deg));
    json_object_set_new(o, "gamma", num(sp->fold_position));
    json_object_set_new(o, "material", text(sp->material));
    json_object_set_new(o, "length_m", num(sp->length_m));
    json_object_set_new(o, "width_m", num(sp->width_m));
    json_object_set_new(o, "thickness_m", num(sp->thickness_m));
    json_object_set_new(o, "youngs_modulus_pa", num(sp->youngs_modulus_pa));
    json_object_set_new(o, "density_kg_m3", num(sp->density_kg_m3));
    json_object_set_new(o, "crease_angle_left_deg", num(sp->crease_angle_left_deg));
    json_object_set_new(o, "crease_angle_right_deg", num(sp->crease_angle_right_deg));
    json_object_set_new(o, "crease_position_left", num(sp->crease_position_left));
    json_object_set_new(o, "crease_position_right", num(sp->crease_position_right));
    json_object_set_new(o, "folded_at", text(sp->folded_at));
    json_object_set_new(o, "crease_orientation", text(sp->crease_orientation));
    json_object_set_new(o, "trials_count", json_integer(sp->trials_count));
    /* Its calibration and the last refit's failure (store v12, trial_specimen_calib.h): stored as
     * JSON objects; an unreadable one is null (never a half-shown record). */
    json_t *cal = sp->calibration_json[0] ? json_loads(sp->calibration_json, 0, NULL) : NULL;
    json_t *fail = sp->calibration_failure_json[0] ? json_loads(sp->calibration_failure_json, 0, NULL) : NULL;
    json_object_set_new(o, "calibration", cal ? cal : json_null());
    json_object_set_new(o, "calibration_failure", fail ? fail : json_null());
    return o;
}

int campaign_specimen_name_ok(const char *name, char *why, size_t why_len)
{
    size_t n = name ? strlen(name) : 0;
    if (n == 0 || n > 63) {
        snprintf(why, why_len, "specimen name must be 1 to 63 bytes (got %zu)", n);
        return 0;
    }
    for (size_t i = 0; i < n; i++) {
        char c = name[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
              c == '-')) {
            snprintf(why, why_len, "specimen name '%.63s': byte %zu is outside [A-Za-z0-9._-] (the name is a path "
                     "segment of the API)", name, i);
            return 0;
        }
    }
    return 1;
}

/* A number field in [lo, hi] (open ends when the flags say so); absent leaves *v. */
static int number(const json_t *body, const char *key, double lo, double hi, int open_lo, int open_hi, double *v,
                  char *why, size_t why_len)
{
    json_t *j = json_object_get(body, key);
    if (!j || json_is_null(j)) return 0;
    if (!json_is_number(j)) {
        snprintf(why, why_len, "field \"%s\" must be a number", key);
        return -1;
    }
    double x = json_number_value(j);
    if (!isfinite(x) || (open_lo ? x <= lo : x < lo) || (open_hi ? x >= hi : x > hi)) {
        snprintf(why, why_len, "field \"%s\" = %g is outside %c%g, %g%c", key, x, open_lo ? '(' : '[', lo, hi,
                 open_hi ? ')' : ']');
        return -1;
    }
    *v = x;
    return 0;
}

static int string(const json_t *body, const char *key, char *dst, size_t cap, char *why, size_t why_len)
{
    json_t *j = json_object_get(body, key);
    if (!j || json_is_null(j)) return 0;
    if (!json_is_string(j) || json_string_length(j) >= cap) {
        snprintf(why, why_len, "field \"%s\" must be a string of at most %zu bytes", key, cap - 1);
        return -1;
    }
    snprintf(dst, cap, "%s", json_string_value(j));
    return 0;
}

int campaign_specimen_measured_from_json(const json_t *body, store_specimen *sp, char *why, size_t why_len)
{
    /* An angle of 0 is no crease, and 180 folds the strip back onto itself: neither can be
     * clamped as a folded ribbon. */
    if (number(body, "crease_angle_left_deg", 0.0, 180.0, 1, 1, &sp->crease_angle_left_deg, why, why_len) ||
        number(body, "crease_angle_right_deg", 0.0, 180.0, 1, 1, &sp->crease_angle_right_deg, why, why_len)) {
        size_t n = strlen(why);
        snprintf(why + n, why_len > n ? why_len - n : 0,
                 ": 0 deg is no crease and 180 folds the strip onto itself; neither can be clamped");
        return -1;
    }
    if (number(body, "crease_position_left", 0.0, 1.0, 1, 1, &sp->crease_position_left, why, why_len) ||
        number(body, "crease_position_right", 0.0, 1.0, 1, 1, &sp->crease_position_right, why, why_len) ||
        string(body, "folded_at", sp->folded_at, sizeof sp->folded_at, why, why_len))
        return -1;
    if (isfinite(sp->crease_position_left) && isfinite(sp->crease_position_right) &&
        !(sp->crease_position_left < sp->crease_position_right)) {
        snprintf(why, why_len, "crease_position_left (%g) must be less than crease_position_right (%g)",
                 sp->crease_position_left, sp->crease_position_right);
        return -1;
    }
    if (sp->folded_at[0]) {
        double t;
        char w[200];
        if (cfg_datetime_parse(sp->folded_at, &t, w, sizeof w) != CFG_DATETIME_OK) {
            snprintf(why, why_len, "field \"folded_at\": %s", w);
            return -1;
        }
    }
    return 0;
}

int campaign_specimen_from_json(const json_t *body, const store_specimen *defaults, store_specimen *out, char *why,
                                size_t why_len)
{
    static const char *const keys[] = {"name", "phi_deg", "gamma", "material", "length_m", "width_m", "thickness_m",
                                       "youngs_modulus_pa", "density_kg_m3", "crease_angle_left_deg",
                                       "crease_angle_right_deg", "crease_position_left", "crease_position_right",
                                       "folded_at", "crease_orientation"};
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)body, k, v)
    {
        size_t i = 0;
        while (i < sizeof keys / sizeof keys[0] && strcmp(keys[i], k) != 0) i++;
        if (i == sizeof keys / sizeof keys[0]) {
            snprintf(why, why_len, "unknown field \"%.64s\" (a specimen has: name, phi_deg, gamma, material, length_m, "
                     "width_m, thickness_m, youngs_modulus_pa, density_kg_m3, crease_angle_left_deg, "
                     "crease_angle_right_deg, crease_position_left, crease_position_right, folded_at, "
                     "crease_orientation)", k);
            return -1;
        }
    }
    store_specimen sp = store_specimen_default();
    sp.length_m = defaults->length_m;
    sp.width_m = defaults->width_m;
    sp.thickness_m = defaults->thickness_m;
    sp.youngs_modulus_pa = defaults->youngs_modulus_pa;
    sp.density_kg_m3 = defaults->density_kg_m3;
    snprintf(sp.material, sizeof sp.material, "%s", defaults->material);
    json_t *name = json_object_get(body, "name");
    if (!json_is_string(name)) {
        snprintf(why, why_len, "field \"name\" (the label written on the strip) is required, a string");
        return -1;
    }
    if (!campaign_specimen_name_ok(json_string_value(name), why, why_len)) return -1;
    snprintf(sp.name, sizeof sp.name, "%s", json_string_value(name));
    if (!json_object_get(body, "phi_deg") || !json_object_get(body, "gamma")) {
        snprintf(why, why_len, "fields \"phi_deg\" and \"gamma\" (the design: fold angle and position) are required");
        return -1;
    }
    if (number(body, "phi_deg", 0.0, 180.0, 1, 1, &sp.phi_deg, why, why_len) ||
        number(body, "gamma", 0.0, 0.5, 1, 0, &sp.fold_position, why, why_len) ||
        number(body, "length_m", 0.0, 100.0, 1, 0, &sp.length_m, why, why_len) ||
        number(body, "width_m", 0.0, 10.0, 1, 0, &sp.width_m, why, why_len) ||
        number(body, "thickness_m", 0.0, 1.0, 1, 0, &sp.thickness_m, why, why_len) ||
        number(body, "youngs_modulus_pa", 0.0, 1e13, 1, 0, &sp.youngs_modulus_pa, why, why_len) ||
        number(body, "density_kg_m3", 0.0, 1e5, 1, 0, &sp.density_kg_m3, why, why_len) ||
        string(body, "material", sp.material, sizeof sp.material, why, why_len) ||
        string(body, "crease_orientation", sp.crease_orientation, sizeof sp.crease_orientation, why, why_len) ||
        campaign_specimen_measured_from_json(body, &sp, why, why_len))
        return -1;
    if (sp.crease_orientation[0] && strcmp(sp.crease_orientation, "up") && strcmp(sp.crease_orientation, "down")) {
        snprintf(why, why_len, "field \"crease_orientation\" must be \"up\" or \"down\"");
        return -1;
    }
    if (!(sp.length_m > 0 && sp.width_m > 0 && sp.thickness_m > 0)) {
        snprintf(why, why_len, "length_m, width_m and thickness_m are required (the rig file's scene gives none)");
        return -1;
    }
    *out = sp;
    return 0;
}

int campaign_specimen_usable(store *st, const char *name, store_specimen *out, char *why, size_t why_len)
{
    char w[256];
    if (!campaign_specimen_name_ok(name, why, why_len)) return -2;
    store_err e = store_specimen_get_by_name(st, name, out, w, sizeof w);
    if (e == STORE_E_NOTFOUND) {
        snprintf(why, why_len, "unknown specimen '%s': no such specimen in the store (ribbonctl specimen add %s "
                 "...); nothing started", name, name);
        return -2;
    }
    if (e != STORE_OK) {
        snprintf(why, why_len, "specimen '%s': %s", name, w);
        return -1;
    }
    if (out->state == STORE_SPECIMEN_RETIRED || out->state == STORE_SPECIMEN_BROKEN) {
        snprintf(why, why_len, "specimen '%s' is %s (%.120s, since %s): a trial may not use it; nothing started", name,
                 store_specimen_state_name(out->state), out->state_reason, out->state_at);
        return -1;
    }
    return 0;
}

int campaign_specimen_overrides(const store_specimen *sp, int scene_sign, campaign_overrides *ov, char *why,
                                size_t why_len)
{
    ov->n = 0;
#define ADD(...)                                                                                                  \
    do {                                                                                                          \
        if (ov->n >= CAMPAIGN_MAX_OVERRIDES) {                                                                    \
            snprintf(why, why_len, "too many specimen overrides");                                                \
            return -1;                                                                                            \
        }                                                                                                         \
        snprintf(ov->text[ov->n], sizeof ov->text[0], __VA_ARGS__);                                               \
        ov->ptr[ov->n] = ov->text[ov->n];                                                                         \
        ov->n++;                                                                                                  \
    } while (0)
    ADD("specimen.name=%s", sp->name);
    if (sp->material[0]) ADD("specimen.material=%s", sp->material);
    ADD("ribbon.length=%.17g", sp->length_m);
    ADD("ribbon.width=%.17g", sp->width_m);
    ADD("ribbon.thickness=%.17g", sp->thickness_m);
    if (isfinite(sp->youngs_modulus_pa)) ADD("ribbon.youngs_modulus=%.17g", sp->youngs_modulus_pa);
    if (isfinite(sp->density_kg_m3)) ADD("ribbon.density=%.17g", sp->density_kg_m3);
    int sign = !strcmp(sp->crease_orientation, "down") ? -1 : !strcmp(sp->crease_orientation, "up") ? 1 : scene_sign;
    if (isfinite(sp->phi_deg)) ADD("folds.angle_deg=%.17g", (sign < 0 ? -1.0 : 1.0) * sp->phi_deg);
    if (isfinite(sp->fold_position)) ADD("folds.position=%.17g", sp->fold_position);
    if (isfinite(sp->crease_angle_left_deg)) ADD("specimen.crease_angle_left_deg=%.17g", sp->crease_angle_left_deg);
    if (isfinite(sp->crease_angle_right_deg)) ADD("specimen.crease_angle_right_deg=%.17g", sp->crease_angle_right_deg);
    if (isfinite(sp->crease_position_left)) ADD("specimen.crease_position_left=%.17g", sp->crease_position_left);
    if (isfinite(sp->crease_position_right)) ADD("specimen.crease_position_right=%.17g", sp->crease_position_right);
    if (sp->folded_at[0]) ADD("specimen.folded_at=%s", sp->folded_at);
    if (sp->crease_orientation[0]) ADD("specimen.crease_orientation=%s", sp->crease_orientation);
#undef ADD
    return 0;
}
