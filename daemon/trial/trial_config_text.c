/* trial_config_text.c: the configuration a trial ran with, as text kept in its row: the rig file
 * and the scene file as they were (each capped at 1 MiB), the overrides applied to them (in
 * order: ribbond's --set, the specimen's record, the start's "set"), and the operator's note; and
 * the scene the trial ran rebuilt from such a text. */
#include "trial_config_text.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg_ini.h"
#include "cfg_number.h"
#include "scene_file.h"

#define OVERRIDES_HEAD "# overrides applied in order after the files: "

/* Appends the file's text (or a note that it could not be read) to a growing buffer. */
static int append_file(char **buf, size_t *len, size_t *cap, const char *label, const char *path)
{
    FILE *f = fopen(path, "rb");
    char head[1200];
    int hn = snprintf(head, sizeof head, "# %s %s\n", label, path);
    size_t need = (size_t)hn + 1;
    long size = 0;
    if (f && fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    if (size < 0 || size > (1 << 20)) size = 0;
    if (f) rewind(f);
    need += (size_t)size + 64;
    if (*len + need > *cap) {
        size_t nc = (*len + need) * 2;
        char *nb = realloc(*buf, nc);
        if (!nb) {
            if (f) fclose(f);
            return -1;
        }
        *buf = nb;
        *cap = nc;
    }
    memcpy(*buf + *len, head, (size_t)hn);
    *len += (size_t)hn;
    if (!f) {
        *len += (size_t)snprintf(*buf + *len, 64, "# (could not be read)\n");
    } else {
        *len += fread(*buf + *len, 1, (size_t)size, f);
        fclose(f);
        if (*len > 0 && (*buf)[*len - 1] != '\n') (*buf)[(*len)++] = '\n';
    }
    (*buf)[*len] = '\0';
    return 0;
}

char *trial_config_text(const rig_config *cfg, const char *const *sets, int n_sets, const char *note)
{
    char *buf = NULL;
    size_t len = 0, cap = 0;
    if (append_file(&buf, &len, &cap, "rig file", cfg->path) ||
        append_file(&buf, &len, &cap, "scene file", cfg->scene_path)) {
        free(buf);
        return NULL;
    }
    /* One line of JSON: an override's value may hold any character, a newline too. No line when
     * the caller does not know them (sets NULL): "not recorded", never a false "none". */
    json_t *arr = sets ? json_array() : NULL;
    for (int k = 0; arr && k < n_sets; k++)
        if (json_array_append_new(arr, json_string(sets[k] ? sets[k] : "")) != 0) {
            json_decref(arr);
            arr = NULL;
        }
    char *js = arr ? json_dumps(arr, JSON_COMPACT | JSON_ENSURE_ASCII) : NULL;
    json_decref(arr);
    if (sets && !js) /* an override that is not UTF-8: said so, and the rebuild refuses it */
        js = strdup("(not readable: an override is not UTF-8 text)");
    if (sets && !js) {
        free(buf);
        return NULL;
    }
    size_t need = js ? strlen(OVERRIDES_HEAD) + strlen(js) + 2 : 0;
    char *nb = js ? realloc(buf, len + need + 1) : buf;
    if (!nb) {
        free(js);
        free(buf);
        return NULL;
    }
    buf = nb;
    if (js) len += (size_t)snprintf(buf + len, need + 1, "%s%s\n", OVERRIDES_HEAD, js);
    free(js);
    if (note && *note) {
        size_t n = strlen(note) + 16;
        char *nb = realloc(buf, len + n + 1);
        if (!nb) {
            free(buf);
            return NULL;
        }
        buf = nb;
        snprintf(buf + len, n + 1, "# note: %s\n", note);
    }
    return buf;
}

/* The start of the last line of text[0, end) that begins with prefix, or NULL. */
static const char *last_line_with(const char *text, const char *end, const char *prefix)
{
    size_t n = strlen(prefix);
    const char *found = NULL;
    for (const char *p = text; p && p < end; p = strchr(p, '\n'), p = p ? p + 1 : NULL)
        if ((size_t)(end - p) >= n && !strncmp(p, prefix, n)) found = p;
    return found;
}

/* The start of the first line of text[0, end) that begins with prefix, or NULL. The overrides
 * line is looked for this way: the note after it is free text (it may hold lines of its own). */
static const char *first_line_with(const char *text, const char *end, const char *prefix)
{
    size_t n = strlen(prefix);
    for (const char *p = text; p && p < end; p = strchr(p, '\n'), p = p ? p + 1 : NULL)
        if ((size_t)(end - p) >= n && !strncmp(p, prefix, n)) return p;
    return NULL;
}

int trial_config_text_scene(const char *text, const char **begin, size_t *len)
{
    const char *end = text + strlen(text);
    const char *head = last_line_with(text, end, "# scene file ");
    if (!head) return -1;
    const char *body = strchr(head, '\n');
    if (!body) return -1;
    body++;
    if (!strncmp(body, "# (could not be read)", 21)) return -1;
    /* What trial_config_text and a replay's row append after the scene: the overrides line
     * first (when stored), else the note, and a replay's line. */
    const char *tail = first_line_with(body, end, OVERRIDES_HEAD);
    if (tail) {
        end = tail;
    } else {
        tail = last_line_with(body, end, "# replay of trial ");
        if (tail) end = tail;
        tail = last_line_with(body, end, "# note: ");
        if (tail) end = tail;
    }
    *begin = body;
    *len = (size_t)(end - body);
    return 0;
}

json_t *trial_config_text_overrides(const char *text)
{
    const char *end = text + strlen(text);
    const char *head = last_line_with(text, end, "# scene file ");
    const char *line = head ? first_line_with(head, end, OVERRIDES_HEAD) : NULL;
    if (!line) return NULL;
    line += strlen(OVERRIDES_HEAD);
    const char *eol = strchr(line, '\n');
    json_t *arr = json_loadb(line, eol ? (size_t)(eol - line) : strlen(line), 0, NULL);
    int ok = json_is_array(arr);
    for (size_t k = 0; ok && k < json_array_size(arr); k++) ok = json_is_string(json_array_get(arr, k));
    if (!ok) {
        json_decref(arr);
        return NULL;
    }
    return arr;
}

/* Whether the override "section.key=value" names one of the scene's sections. */
static int is_scene_override(const char *ovr)
{
    const char *eq = strchr(ovr, '=');
    const char *stop = eq ? eq : ovr + strlen(ovr);
    const char *dot = NULL;
    for (const char *p = ovr; p < stop; p++)
        if (*p == '.') dot = p;
    if (!dot) return 0;
    while (ovr < dot && (*ovr == ' ' || *ovr == '\t')) ovr++;
    size_t n;
    const cfg_scene_key *k = cfg_scene_keys(&n);
    for (size_t i = 0; i < n; i++)
        if (strlen(k[i].section) == (size_t)(dot - ovr) && !strncmp(k[i].section, ovr, (size_t)(dot - ovr))) return 1;
    return 0;
}

int trial_config_text_scene_load(const char *text, const char *name, rod_scene *out, char *why, size_t why_len)
{
    const char *begin;
    size_t len;
    if (trial_config_text_scene(text, &begin, &len)) {
        snprintf(why, why_len, "its stored configuration holds no readable scene file");
        return -1;
    }
    json_t *arr = trial_config_text_overrides(text);
    const char *end = text + strlen(text);
    if (!arr && first_line_with(begin + len, end, OVERRIDES_HEAD)) {
        snprintf(why, why_len, "its stored overrides cannot be read");
        return -1;
    }
    size_t n = json_array_size(arr);
    const char **sets = calloc(n ? n : 1, sizeof *sets);
    if (!sets) {
        json_decref(arr);
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    int ns = 0;
    for (size_t k = 0; k < n; k++) {
        const char *o = json_string_value(json_array_get(arr, k));
        if (is_scene_override(o)) sets[ns++] = o;
    }
    cfg_error ce;
    cfg_status cs = cfg_scene_parse(name, begin, len, sets, ns, out, &ce);
    free(sets);
    json_decref(arr);
    if (cs != CFG_OK) {
        char w[400];
        cfg_error_format(&ce, w, sizeof w);
        snprintf(why, why_len, "its stored scene cannot be read: %s", w);
        return -1;
    }
    return 0;
}

/* The two fit keys of the rig file's [sim] section, as read so far. */
typedef struct fit_read {
    double hinge;
    char keys[256];
    int bad;          /* a value the rig loader would have refused */
    char what[160];
} fit_read;

/* One "sim.KEY" value: fit_hinge a number in [0, 1e6] (the rig table's range), fit_keys text. */
static void fit_value(fit_read *f, const char *name, const char *value)
{
    if (!strcmp(name, "fit_keys")) {
        snprintf(f->keys, sizeof f->keys, "%s", value);
    } else if (!strcmp(name, "fit_hinge")) {
        double v;
        if (cfg_number_parse(value, &v) != CFG_NUMBER_OK || !(v >= 0.0 && v <= 1e6)) {
            f->bad = 1;
            snprintf(f->what, sizeof f->what, "sim.fit_hinge = %.100s is not a stiffness in [0, 1e6] N m/rad", value);
        } else
            f->hinge = v;
    }
}

static int fit_key_cb(void *user, int line, const char *section, const char *name, const char *value)
{
    (void)line;
    if (!strcmp(section, "sim")) fit_value(user, name, value);
    return 0;
}

static int fit_section_cb(void *user, int line, const char *section)
{
    (void)user;
    (void)line;
    (void)section;
    return 0;
}

int trial_config_text_fit(const char *text, double *fit_hinge, char *keys, size_t keys_len, char *why,
                          size_t why_len)
{
    fit_read f;
    memset(&f, 0, sizeof f);
    const char *end = text + strlen(text);
    const char *head = first_line_with(text, end, "# rig file ");
    const char *scene = head ? first_line_with(head, end, "# scene file ") : NULL;
    const char *body = head ? strchr(head, '\n') : NULL;
    if (!head || !scene || !body || body + 1 > scene || !strncmp(body + 1, "# (could not be read)", 21)) {
        snprintf(why, why_len, "its stored configuration holds no readable rig file (sim.fit_hinge, sim.fit_keys)");
        return -1;
    }
    body++;
    cfg_ini_handler h = {.section = fit_section_cb, .key = fit_key_cb};
    cfg_error ce;
    if (cfg_ini_parse("the stored rig file", body, (size_t)(scene - body), &h, &f, &ce) != CFG_OK) {
        char w[300];
        cfg_error_format(&ce, w, sizeof w);
        snprintf(why, why_len, "its stored rig file cannot be read: %s", w);
        return -1;
    }
    json_t *arr = trial_config_text_overrides(text);
    for (size_t k = 0; k < json_array_size(arr); k++) {
        const char *o = json_string_value(json_array_get(arr, k));
        while (*o == ' ' || *o == '\t') o++;
        const char *eq = strchr(o, '=');
        if (!eq || strncmp(o, "sim.", 4)) continue;
        char name[32];
        size_t n = (size_t)(eq - o - 4);
        while (n > 0 && (o[4 + n - 1] == ' ' || o[4 + n - 1] == '\t')) n--;
        if (n >= sizeof name) continue;
        memcpy(name, o + 4, n);
        name[n] = '\0';
        const char *v = eq + 1;
        while (*v == ' ' || *v == '\t') v++;
        fit_value(&f, name, v);
    }
    json_decref(arr);
    if (f.bad) {
        snprintf(why, why_len, "its stored %s", f.what);
        return -1;
    }
    *fit_hinge = f.hinge;
    snprintf(keys, keys_len, "%s", f.keys);
    return 0;
}

void trial_config_text_add_overrides(store *st, int64_t id, json_t *trial)
{
    char *text = NULL, w[256];
    json_t *arr = NULL;
    if (store_trial_texts(st, id, &text, NULL, w, sizeof w) == STORE_OK && text) arr = trial_config_text_overrides(text);
    free(text);
    json_object_set_new(trial, "overrides", arr ? arr : json_null());
}
