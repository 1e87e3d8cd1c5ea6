/* cfg_error.c: formatting of config errors into the one-line "FILE:LINE: section.key: message"
 * form every loader prints. Kept tiny and allocation-free (see cfg_error.h). */
#include "cfg_error.h"

#include <stdio.h>
#include <string.h>

void cfg_error_clear(cfg_error *err)
{
    if (err) memset(err, 0, sizeof *err);
}

char *cfg_error_format(const cfg_error *err, char *buf, size_t len)
{
    if (!buf || len == 0) return buf;
    buf[0] = '\0';
    if (!err) return buf;
    int n;
    switch (err->origin) {
    case CFG_ORIGIN_LINE:
        n = snprintf(buf, len, "%s:%d: ", err->file, err->line);
        break;
    case CFG_ORIGIN_OVERRIDE:
        n = snprintf(buf, len, "%s %s: ", err->file, err->where);
        break;
    case CFG_ORIGIN_DEFAULT:
        n = snprintf(buf, len, "%s:%s: ", err->file, err->where[0] ? err->where : "default");
        break;
    case CFG_ORIGIN_FILE:
    default:
        n = snprintf(buf, len, "%s: ", err->file);
        break;
    }
    if (n < 0 || (size_t)n >= len) return buf;
    size_t used = (size_t)n;
    if (err->key[0]) {
        n = snprintf(buf + used, len - used, "%s: ", err->key);
        if (n < 0 || (size_t)n >= len - used) return buf;
        used += (size_t)n;
    }
    snprintf(buf + used, len - used, "%s", err->message);
    return buf;
}
