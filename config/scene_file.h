/* scene_file.h: load a scene INI file (config/scenes/NAME.ini) into a rod_scene, with
 * `--set section.key=value` overrides applied after the file.
 *
 * One key table (cfg_scene_keys()) drives parsing, bounds checking and the README's
 * "Scene files" table: each key has a section, a name, a type, bounds, an offset into rod_scene,
 * a unit, whether it is required, and a doc string. The loader starts from rod_scene_default(),
 * so a key that is not required keeps its documented default, and finishes with rod_scene_check()
 * for the checks that involve several keys. Every error names the file, the line (or the
 * override) and the "section.key" at fault; see cfg_error.h. */
#ifndef RIBBON_CONFIG_SCENE_FILE_H
#define RIBBON_CONFIG_SCENE_FILE_H

#include <stddef.h>

#include "cfg_error.h"
#include "scene.h"

/* Value types of scene keys. */
typedef enum cfg_type {
    CFG_TYPE_DOUBLE, /* one finite decimal number */
    CFG_TYPE_INT,    /* one decimal integer */
    CFG_TYPE_VEC3,   /* three finite numbers separated by spaces or commas: "0 0 -9.81" */
    CFG_TYPE_ENUM,   /* one of the names in `names` (protocol.route) */
    CFG_TYPE_DOUBLE_OR_WORD /* one finite number in the bounds, or the word names[0], which
                               stores +infinity (folds.hinge_stiffness = rigid) */
} cfg_type;

/* Flags of a key. */
enum {
    CFG_KEY_REQUIRED = 1u << 0, /* must appear in the file; no default is used */
    CFG_KEY_MIN_OPEN = 1u << 1, /* the lower bound itself is refused: (min, ... */
    CFG_KEY_MAX_OPEN = 1u << 2  /* the upper bound itself is refused: ..., max) */
};

/* One row of the key table. For VEC3 the bounds apply to each component; for ENUM they are
 * unused and `names` lists the accepted names in the order of the C enum's values 0, 1, ...
 * For DOUBLE_OR_WORD, names[0] is the word. */
typedef struct cfg_scene_key {
    const char *section;
    const char *name;
    cfg_type type;
    size_t offset;              /* offsetof(rod_scene, field) */
    double min, max;            /* inclusive unless CFG_KEY_MIN_OPEN / CFG_KEY_MAX_OPEN */
    unsigned flags;
    const char *const *names;   /* ENUM only, NULL-terminated */
    const char *unit;           /* "m", "Pa", "1" (dimensionless), ... */
    const char *doc;            /* one sentence: meaning, and the default's rationale */
} cfg_scene_key;

/* The table, in file order ([ribbon] [folds] [imperfection] [mesh] [protocol] [solver] [snap]).
 * Stored in *n. The table is static, read-only data. */
const cfg_scene_key *cfg_scene_keys(size_t *n);

/* Longest file the loader reads, and longest line (bytes, without the newline). */
#define CFG_SCENE_MAX_FILE_BYTES (1u << 20)
#define CFG_SCENE_MAX_LINE 160

/* Load `path`, apply the n_overrides strings "section.key=value" in order (a later override of the
 * same key wins), check the result, and on success store it in *out. On failure *out is left
 * untouched and *err (if not NULL) says why. Returns CFG_OK (0) or the status of the error. */
cfg_status cfg_scene_load(const char *path, const char *const *overrides, int n_overrides,
                          rod_scene *out, cfg_error *err);

/* The same on text already in memory (`len` bytes, need not be NUL-terminated); `name` is used as
 * the file name in errors. For tests, fuzzing, and scenes stored in the trial database. */
cfg_status cfg_scene_parse(const char *name, const char *text, size_t len,
                           const char *const *overrides, int n_overrides,
                           rod_scene *out, cfg_error *err);

/* Apply the n_overrides strings "section.key=value" in order to a copy of `base` (a scene already
 * loaded and checked) through the same key table and value rules as a file's --set, then check the
 * result as a load does (rod_scene_check). `name` names the result in errors that blame a value of
 * `base` (a cross-field check), e.g. "twin". On success the result goes to *out (which may be
 * base); on failure *out is untouched and *err says why: an override's error names the override
 * text (CFG_ORIGIN_OVERRIDE, its text in err->where). Mock mode's twin is built with this
 * (rig_config.h [twin]), so every scene key is a twin key without a second table. */
cfg_status cfg_scene_apply(const rod_scene *base, const char *name, const char *const *overrides,
                           int n_overrides, rod_scene *out, cfg_error *err);

#endif
