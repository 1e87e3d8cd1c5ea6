/* cfg_ini.c: the line-exact INI reader (see cfg_ini.h). Owns the rules of the file format that
 * are common to every loader; what a section or key means is the caller's business.
 *
 * inih reads through line_read(), which hands out exactly one physical line per call, checks it
 * the way inih will read it (line_check) and reports section headers with their line. inih then
 * calls on_key() for each "key = value" with the current line number known. The first error wins;
 * later lines are still handed to inih (it has no way to stop from the reader) but ignored. */
#include "cfg_ini.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <ctype.h>
#include <errno.h>
#include <ini.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct ini_ctx {
    const char *name;
    const char *text;
    size_t len;
    size_t pos;     /* next byte the reader hands out */
    int lineno;     /* physical lines handed to inih so far = the current line */
    const cfg_ini_handler *h;
    void *user;
    cfg_error *err;
    int failed;
} ini_ctx;

void cfg_text_printable(char *dst, size_t dstlen, const char *src, size_t srclen)
{
    if (!dst || dstlen == 0) return;
    size_t n = 0;
    for (size_t i = 0; src && i < srclen && src[i] && n + 1 < dstlen; i++) {
        unsigned char ch = (unsigned char)src[i];
        dst[n++] = (ch >= 0x20 && ch < 0x7f) ? (char)ch : '?';
    }
    dst[n] = '\0';
}

cfg_status cfg_error_set(cfg_error *err, cfg_status st, cfg_origin origin, const char *file,
                         int line, const char *where, const char *key, const char *fmt, ...)
{
    if (!err) return st;
    cfg_error_clear(err);
    err->status = st;
    err->origin = origin;
    err->line = origin == CFG_ORIGIN_LINE ? line : 0;
    snprintf(err->file, sizeof err->file, "%s", file ? file : "");
    cfg_text_printable(err->where, sizeof err->where, where, where ? strlen(where) : 0);
    cfg_text_printable(err->key, sizeof err->key, key, key ? strlen(key) : 0);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return st;
}

cfg_status cfg_error_from(cfg_error *err, cfg_status st, const char *file, int line,
                          const char *ovr, const char *key, const char *msg)
{
    if (ovr) return cfg_error_set(err, st, CFG_ORIGIN_OVERRIDE, "--set", 0, ovr, key, "%s", msg);
    if (line > 0) return cfg_error_set(err, st, CFG_ORIGIN_LINE, file, line, NULL, key, "%s", msg);
    return cfg_error_set(err, st, CFG_ORIGIN_DEFAULT, file, 0, "default", key, "%s", msg);
}

int cfg_ini_count_lines(const char *text, size_t len)
{
    int lines = 0;
    for (size_t i = 0; i < len; i++)
        if (text[i] == '\n') lines++;
    if (len > 0 && text[len - 1] != '\n') lines++;
    return lines;
}

/* The first syntax error at the current line; `key` (may be NULL) goes to cfg_error.key. */
static void fail_line_key(ini_ctx *c, const char *key, const char *fmt, const char *arg)
{
    if (c->failed) return;
    c->failed = 1;
    cfg_error_set(c->err, CFG_ERR_SYNTAX, CFG_ORIGIN_LINE, c->name, c->lineno, NULL, key, fmt,
                  arg ? arg : "");
}

static void fail_line(ini_ctx *c, const char *fmt, const char *arg)
{
    fail_line_key(c, NULL, fmt, arg);
}

/* The handler's longest line (see cfg_ini_handler.max_line). */
static size_t max_line(const ini_ctx *c)
{
    size_t m = c->h->max_line;
    return m == 0 || m > CFG_INI_MAX_LINE ? CFG_INI_MAX_LINE : m;
}

/* Check one line (leading whitespace already removed, no newline) the way inih will read it. */
static void line_check(ini_ctx *c, const char *line, size_t n)
{
    while (n > 0 && isspace((unsigned char)line[n - 1])) n--;
    if (n == 0 || line[0] == ';' || line[0] == '#') return;
    if (line[0] == '[') {
        size_t i = 1;
        while (i < n && line[i] != ']') i++;
        if (i >= n) {
            fail_line(c, "section header without a closing ']'%s", NULL);
            return;
        }
        for (size_t j = 2; j < i; j++) {
            if (line[j] == ';' && isspace((unsigned char)line[j - 1])) {
                fail_line(c, "comment inside a section header%s", NULL);
                return;
            }
        }
        size_t r = i + 1;
        while (r < n && isspace((unsigned char)line[r])) r++;
        if (r < n && line[r] != ';' && line[r] != '#') {
            fail_line(c, "unexpected text after the section header%s", NULL);
            return;
        }
        char name[CFG_INI_MAX_LINE + 1]; /* i - 1 < n <= max_line(c) */
        memcpy(name, line + 1, i - 1);
        name[i - 1] = '\0';
        if (c->h->section && c->h->section(c->user, c->lineno, name)) c->failed = 1;
        return;
    }
    /* key = value: inih splits at the first '=' or ':' not inside an inline comment. */
    for (size_t i = 0; i < n; i++) {
        if (line[i] == '=') return;
        if (line[i] == ':') {
            fail_line(c, "expected 'key = value' ('=' not ':')%s", NULL);
            return;
        }
        if (line[i] == ';' && i > 0 && isspace((unsigned char)line[i - 1])) break;
    }
    fail_line(c, "expected 'key = value', '[section]' or a comment%s", NULL);
}

/* inih reader: one physical line per call. Strips a UTF-8 BOM on line 1, leading whitespace and
 * a trailing '\r'. */
static char *line_read(char *str, int num, void *stream)
{
    ini_ctx *c = stream;
    if (c->pos >= c->len || num < 3) return NULL;
    size_t start = c->pos, end = c->pos;
    while (end < c->len && c->text[end] != '\n') end++;
    c->pos = end < c->len ? end + 1 : end;
    c->lineno++;
    if (c->lineno == 1 && end - start >= 3 && (unsigned char)c->text[start] == 0xEF &&
        (unsigned char)c->text[start + 1] == 0xBB && (unsigned char)c->text[start + 2] == 0xBF)
        start += 3;
    if (end > start && c->text[end - 1] == '\r') end--;
    while (start < end && isspace((unsigned char)c->text[start])) start++;

    size_t n = end - start;
    const char *nul = memchr(c->text + start, '\0', n);
    if (nul) {
        fail_line(c, "NUL byte in the line (not a text file?)%s", NULL);
        n = (size_t)(nul - (c->text + start));
    }
    size_t cap = (size_t)num - 2; /* room for '\n' and '\0' */
    if (cap > max_line(c)) cap = max_line(c);
    if (n > cap) {
        char msg[64];
        snprintf(msg, sizeof msg, "%zu", max_line(c));
        fail_line(c, "line longer than %s characters", msg);
        n = cap;
    }
    memcpy(str, c->text + start, n);
    str[n] = '\n';
    str[n + 1] = '\0';
    if (!c->failed) line_check(c, str, n);
    return str;
}

static int on_key(void *user, const char *section, const char *name, const char *value)
{
    ini_ctx *c = user;
    if (c->failed) return 1; /* only the first error is reported */
    if (section[0] == '\0') {
        char shown[64];
        cfg_text_printable(shown, sizeof shown, name, strlen(name));
        fail_line_key(c, c->h->name_keys ? name : NULL, "key '%s' before any [section]", shown);
        return 0;
    }
    if (name[0] == '\0') {
        char dotted[128];
        snprintf(dotted, sizeof dotted, "%s.", section);
        fail_line_key(c, c->h->name_keys ? dotted : NULL, "empty key name before '='%s", NULL);
        return 0;
    }
    if (c->h->key && c->h->key(c->user, c->lineno, section, name, value)) {
        c->failed = 1;
        return 0;
    }
    return 1;
}

cfg_status cfg_ini_parse(const char *name, const char *text, size_t len, const cfg_ini_handler *h,
                         void *user, cfg_error *err)
{
    cfg_error local;
    if (!err) err = &local;
    cfg_error_clear(err);
    ini_ctx c;
    memset(&c, 0, sizeof c);
    c.name = name ? name : "(config)";
    c.text = text ? text : "";
    c.len = text ? len : 0;
    c.h = h;
    c.user = user;
    c.err = err;
    int rc = ini_parse_stream(line_read, &c, on_key, &c);
    if (!c.failed && rc != 0) {
        /* inih saw an error line_check did not (should not happen: it mirrors inih). */
        if (rc > 0) {
            c.lineno = rc;
            fail_line(&c, "malformed line%s", NULL);
        } else {
            cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, c.name, 0, NULL, NULL,
                          "the INI parser failed (out of memory?)");
            c.failed = 1;
        }
    }
    return c.failed ? (err->status ? err->status : CFG_ERR_SYNTAX) : CFG_OK;
}

const char *cfg_file_kind(unsigned mode)
{
    if (S_ISDIR(mode)) return "a directory";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISSOCK(mode)) return "a socket";
    if (S_ISREG(mode)) return "a regular file";
    return "not a regular file";
}

FILE *cfg_open_regular(const char *path, char *why, size_t why_len)
{
    /* O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer, for ever. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) {
        snprintf(why, why_len, "cannot open: %s", strerror(errno));
        return NULL;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        snprintf(why, why_len, "cannot stat: %s", strerror(errno));
        close(fd);
        return NULL;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(why, why_len, "not a regular file (%s)", cfg_file_kind((unsigned)st.st_mode));
        close(fd);
        return NULL;
    }
    int fl = fcntl(fd, F_GETFL);
    if (fl >= 0) (void)fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        snprintf(why, why_len, "cannot open: %s", strerror(errno));
        close(fd);
    }
    return f;
}

cfg_status cfg_ini_read_file(const char *path, size_t max_bytes, char **text, size_t *len,
                             cfg_error *err)
{
    cfg_error local;
    if (!err) err = &local;
    *text = NULL;
    *len = 0;
    if (!path)
        return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, "(null)", 0, NULL, NULL,
                             "no file given");
    char why[160];
    FILE *f = cfg_open_regular(path, why, sizeof why);
    if (!f)
        return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, path, 0, NULL, NULL, "%s", why);
    char *buf = malloc(max_bytes + 1);
    if (!buf) {
        fclose(f);
        return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, path, 0, NULL, NULL,
                             "out of memory");
    }
    size_t n = fread(buf, 1, max_bytes + 1, f);
    int read_error = ferror(f);
    fclose(f);
    if (read_error || n > max_bytes) {
        free(buf);
        if (read_error)
            return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, path, 0, NULL, NULL,
                                 "read error (is it a directory?)");
        return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, path, 0, NULL, NULL,
                             "file larger than %zu bytes; not a config file", max_bytes);
    }
    buf[n] = '\0';
    *text = buf;
    *len = n;
    return CFG_OK;
}
