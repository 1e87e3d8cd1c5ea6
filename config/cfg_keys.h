/* cfg_keys.h: what every table-driven config loader does with its own key table (the scene's
 * cfg_scene_key rows, the rig's rig_key rows): find a key by section and name or by
 * "section.key", list a section's keys for an "unknown key" error, find a section among a list of
 * names, join an enum's names, describe and check a key's bounds, and split a
 * `--set section.key=value` override into its trimmed halves.
 *
 * The two tables have different row types. A cfg_key_table says how long a row is and where its
 * `const char *section` and `const char *name` fields sit (offsetof), so one lookup serves both
 * without casting one struct type to another. The messages stay the loaders' own: these helpers
 * only find, join and check. Nothing here allocates or keeps state. */
#ifndef RIBBON_CONFIG_CFG_KEYS_H
#define RIBBON_CONFIG_CFG_KEYS_H

#include <stddef.h>

/* A read-only view of a key table: n rows of `stride` bytes at `rows`. */
typedef struct cfg_key_table {
    const void *rows;
    size_t n;
    size_t stride;      /* sizeof one row */
    size_t section_off; /* offsetof(row, section), a const char * */
    size_t name_off;    /* offsetof(row, name), a const char * */
} cfg_key_table;

/* Initializer of a cfg_key_table over a static array `rows` of `type` (a constant expression). */
#define CFG_KEY_TABLE(rows, type)                                                                  \
    {(rows), sizeof(rows) / sizeof((rows)[0]), sizeof(type), offsetof(type, section),             \
     offsetof(type, name)}

/* Index of the row with this section and name, or -1. */
int cfg_keys_find(const cfg_key_table *t, const char *section, const char *name);

/* Index of the row named by "section.name", or -1. The section may itself contain dots. */
int cfg_keys_find_dotted(const cfg_key_table *t, const char *dotted);

/* The names of the section's keys in table order, separated by single spaces, into buf (len > 0).
 * Stops before the first name that does not fit whole. Returns buf. */
char *cfg_keys_known(const cfg_key_table *t, const char *section, char *buf, size_t len);

/* Index of `name` among the n strings of `names`, or -1. */
int cfg_names_find(const char *const *names, size_t n, const char *name);

/* The NULL-terminated `names` joined with " | " into buf (len > 0), e.g. "off | on"; a name that
 * does not fit is cut and ends the list. Returns buf. */
char *cfg_names_join(const char *const *names, char *buf, size_t len);

/* Whether v lies within [min, max], an open end refusing the bound itself. NaN is out. */
int cfg_in_range(double v, double min, double max, int min_open, int max_open);

/* The allowed range as the loaders print it, e.g. "(0, 100] m"; no unit for "1" and "-". */
void cfg_range_text(char *buf, size_t len, double min, double max, int min_open, int max_open,
                    const char *unit);

/* How an override "section.key=value" split (cfg_override_split). */
typedef enum cfg_split {
    CFG_SPLIT_OK = 0,
    CFG_SPLIT_NO_EQUALS,     /* NULL, or no '=' in the text */
    CFG_SPLIT_KEY_TOO_LONG,  /* the trimmed part before '=' does not fit in key */
    CFG_SPLIT_VALUE_TOO_LONG /* the trimmed part after the first '=' does not fit in value */
} cfg_split;

/* Split `ovr` at its first '=' into the key and the value, each with surrounding whitespace
 * removed. On CFG_SPLIT_VALUE_TOO_LONG the key has been filled. */
cfg_split cfg_override_split(const char *ovr, char *key, size_t keylen, char *value,
                             size_t valuelen);

#endif
