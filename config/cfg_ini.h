/* cfg_ini.h: line-exact INI reading on top of inih, for config loaders that must name the line
 * of every error (the scene file loader and the rig file loader).
 *
 * inih does the splitting (sections, "key = value", inline " ;" comments, whitespace). This module
 * feeds it one physical line per reader call, so the count of calls is the line number (Debian
 * builds inih without line numbers in the handler), and it refuses what inih would accept silently
 * or mangle: NUL bytes, over-long lines (inih would split them), "key: value", text after a
 * "[section]", keys before any section, empty key names. How long a section name may be, and which
 * sections exist, is the section callback's to say (it sees the whole name). Leading whitespace is stripped, so an indented line is
 * never a continuation of the previous value. CRLF line ends and a UTF-8 BOM are accepted.
 * No global state: inih's options are compile-time, and every call has its own context. */
#ifndef RIBBON_CONFIG_CFG_INI_H
#define RIBBON_CONFIG_CFG_INI_H

#include <stddef.h>
#include <stdio.h>

#include "cfg_error.h"

/* Longest line the reader accepts (bytes, without the newline). inih's line buffer is 200 bytes
 * (INI_MAX_LINE in Debian's build), less the newline and the terminator. */
#define CFG_INI_MAX_LINE 196

/* Callbacks, and the two points where the loaders' file formats differ. Each callback returns 0 to
 * go on; non-zero stops the read, and the callback must have filled the cfg_error (cfg_error_set)
 * before returning. `line` is 1-based. Initialise with designated initializers: a field left out
 * is 0, the default. */
typedef struct cfg_ini_handler {
    int (*section)(void *user, int line, const char *section);
    int (*key)(void *user, int line, const char *section, const char *name, const char *value);
    size_t max_line;  /* longest line accepted (bytes, without the newline); 0 or more than
                         CFG_INI_MAX_LINE: CFG_INI_MAX_LINE */
    int name_keys;    /* 1: the errors "key before any [section]" and "empty key name" name the key
                         in cfg_error.key ("name", "section."), as the scene loader does; 0: they
                         name none, as the rig loader does */
} cfg_ini_handler;

/* Read `len` bytes of `text` (need not be NUL-terminated); `name` is the file name for errors.
 * Syntax errors are reported in *err with the line and status CFG_ERR_SYNTAX. Returns CFG_OK, the
 * status a callback left in *err, or CFG_ERR_IO when inih fails (out of memory). */
cfg_status cfg_ini_parse(const char *name, const char *text, size_t len, const cfg_ini_handler *h,
                         void *user, cfg_error *err);

/* Lines in `len` bytes of text as cfg_ini_parse counts them: a last line without a newline counts.
 * The line a loader names for a key missing from an absent section. */
int cfg_ini_count_lines(const char *text, size_t len);

/* Open path for reading only if it is a regular file: a FIFO, a device (/dev/zero), a directory
 * or a socket is refused without blocking (the open is non-blocking, so a FIFO with no writer
 * cannot hang the caller), with the reason in why ("not a regular file (a FIFO)"). NULL on
 * failure. Every config and scene file is opened through here. */
FILE *cfg_open_regular(const char *path, char *why, size_t why_len);

/* What kind of file st_mode is, for messages: "a directory", "a FIFO", "a character device"... */
const char *cfg_file_kind(unsigned mode);

/* Read a whole file of at most max_bytes into a malloc'd, NUL-terminated buffer (*text, *len).
 * On failure nothing is allocated and *err names the file (CFG_ERR_IO). */
cfg_status cfg_ini_read_file(const char *path, size_t max_bytes, char **text, size_t *len,
                             cfg_error *err);

/* Fill *err (clearing it first). origin CFG_ORIGIN_LINE needs line >= 1; `where` is the override
 * text or "default" (may be NULL); `key` the "section.key" (may be NULL). Returns st. */
cfg_status cfg_error_set(cfg_error *err, cfg_status st, cfg_origin origin, const char *file,
                         int line, const char *where, const char *key, const char *fmt, ...)
    __attribute__((format(printf, 8, 9)));

/* Fill *err (as cfg_error_set, message `msg`) blaming where a value came from: the `--set`
 * override whose text is `ovr` when ovr is not NULL, else line `line` of `file` when line > 0,
 * else the built-in default (where = "default"). Returns st. */
cfg_status cfg_error_from(cfg_error *err, cfg_status st, const char *file, int line,
                          const char *ovr, const char *key, const char *msg);

/* Copy at most srclen bytes of src into dst for an error message, non-printable bytes as '?', so a
 * corrupt file cannot put control characters on the user's terminal. Always terminates. */
void cfg_text_printable(char *dst, size_t dstlen, const char *src, size_t srclen);

#endif
