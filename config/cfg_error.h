/* cfg_error.h: the error every config loader returns: which file, which line (or which override),
 * which "section.key", and a human message, plus a status code a caller can branch on.
 *
 * Owned here, apart from any one loader, so that a rig file loader that points at a scene can pass
 * a scene error up unchanged. Fixed-size buffers: an error never allocates, so it can be filled on
 * any failure path (including out-of-memory) and copied by value. */
#ifndef RIBBON_CONFIG_CFG_ERROR_H
#define RIBBON_CONFIG_CFG_ERROR_H

#include <stddef.h>

/* What went wrong. CFG_OK is 0 so `if (cfg_...(...))` reads as "if it failed". */
typedef enum cfg_status {
    CFG_OK = 0,
    CFG_ERR_IO,        /* the file cannot be opened or read, or is too large */
    CFG_ERR_SYNTAX,    /* a line is neither a comment, a [section] nor key = value */
    CFG_ERR_UNKNOWN,   /* unknown section or key */
    CFG_ERR_DUPLICATE, /* a key set twice in one file */
    CFG_ERR_MISSING,   /* a required key is absent */
    CFG_ERR_VALUE,     /* a value that does not parse: empty, trailing text, non-finite, bad enum */
    CFG_ERR_RANGE,     /* a value outside the key's bounds */
    CFG_ERR_CHECK      /* the values parse, but together they describe an impossible setup */
} cfg_status;

/* Where the offending value came from. */
typedef enum cfg_origin {
    CFG_ORIGIN_FILE = 0, /* the file as a whole (I/O), `line` is 0 */
    CFG_ORIGIN_LINE,     /* a line of the file, `line` >= 1 */
    CFG_ORIGIN_OVERRIDE, /* a `--set` override, its text in `where` */
    CFG_ORIGIN_DEFAULT   /* a built-in default the file did not set; `where` is "default" */
} cfg_origin;

typedef struct cfg_error {
    cfg_status status;
    cfg_origin origin;
    char file[256];     /* the file name as given; "--set" for an override */
    int line;           /* 1-based line when origin is CFG_ORIGIN_LINE, else 0 */
    char where[160];    /* the override text ("ribbon.length=2"), or "default", or "" */
    char key[96];       /* "section.key", or "" when no key is involved */
    char message[512];  /* what is wrong and, where it helps, what is allowed */
} cfg_error;

/* Format as one line:
 *   FILE:LINE: section.key: message          (a line of the file)
 *   --set section.key=value: section.key: m  (an override)
 *   FILE:default: section.key: message       (a default the file did not set)
 *   FILE: message                            (the file as a whole)
 * Always NUL-terminates (when len > 0), truncating if needed. Returns buf. */
char *cfg_error_format(const cfg_error *err, char *buf, size_t len);

/* Reset to "no error". */
void cfg_error_clear(cfg_error *err);

#endif
