/* cfg_keys.c: key-table lookups, bounds and override splitting shared by the table-driven config
 * loaders (see cfg_keys.h). Rows are reached through the table's stride and field offsets only;
 * the field at those offsets is a `const char *`, so reading it as one is well-defined for any
 * row type. */
#include "cfg_keys.h"

#include <ctype.h>
#include <stdio.h>
#include <string.h>

static const char *row_text(const cfg_key_table *t, size_t i, size_t off)
{
    const char *const *field = (const void *)((const char *)t->rows + i * t->stride + off);
    return *field;
}

int cfg_keys_find(const cfg_key_table *t, const char *section, const char *name)
{
    for (size_t i = 0; i < t->n; i++)
        if (strcmp(section, row_text(t, i, t->section_off)) == 0 &&
            strcmp(name, row_text(t, i, t->name_off)) == 0)
            return (int)i;
    return -1;
}

int cfg_keys_find_dotted(const cfg_key_table *t, const char *dotted)
{
    for (size_t i = 0; i < t->n; i++) {
        const char *section = row_text(t, i, t->section_off);
        size_t ls = strlen(section);
        if (strncmp(dotted, section, ls) == 0 && dotted[ls] == '.' &&
            strcmp(dotted + ls + 1, row_text(t, i, t->name_off)) == 0)
            return (int)i;
    }
    return -1;
}

char *cfg_keys_known(const cfg_key_table *t, const char *section, char *buf, size_t len)
{
    buf[0] = '\0';
    size_t used = 0;
    for (size_t i = 0; i < t->n; i++) {
        if (strcmp(row_text(t, i, t->section_off), section) != 0) continue;
        int w = snprintf(buf + used, len - used, "%s%s", used ? " " : "",
                         row_text(t, i, t->name_off));
        if (w < 0 || (size_t)w >= len - used) break;
        used += (size_t)w;
    }
    return buf;
}

int cfg_names_find(const char *const *names, size_t n, const char *name)
{
    for (size_t i = 0; i < n; i++)
        if (strcmp(name, names[i]) == 0) return (int)i;
    return -1;
}

char *cfg_names_join(const char *const *names, char *buf, size_t len)
{
    buf[0] = '\0';
    size_t used = 0;
    for (int i = 0; names && names[i]; i++) {
        int w = snprintf(buf + used, len - used, "%s%s", i ? " | " : "", names[i]);
        if (w < 0 || (size_t)w >= len - used) break;
        used += (size_t)w;
    }
    return buf;
}

int cfg_in_range(double v, double min, double max, int min_open, int max_open)
{
    if (min_open ? !(v > min) : !(v >= min)) return 0;
    if (max_open ? !(v < max) : !(v <= max)) return 0;
    return 1;
}

void cfg_range_text(char *buf, size_t len, double min, double max, int min_open, int max_open,
                    const char *unit)
{
    int plain = strcmp(unit, "1") == 0 || strcmp(unit, "-") == 0;
    snprintf(buf, len, "%c%.10g, %.10g%c%s%s", min_open ? '(' : '[', min, max,
             max_open ? ')' : ']', plain ? "" : " ", plain ? "" : unit);
}

/* Copy [b, e), trimmed of whitespace at both ends, into dst. -1 if it does not fit. */
static int copy_trimmed(char *dst, size_t dstlen, const char *b, const char *e)
{
    while (b < e && isspace((unsigned char)*b)) b++;
    while (e > b && isspace((unsigned char)e[-1])) e--;
    if ((size_t)(e - b) >= dstlen) return -1;
    memcpy(dst, b, (size_t)(e - b));
    dst[e - b] = '\0';
    return 0;
}

cfg_split cfg_override_split(const char *ovr, char *key, size_t keylen, char *value,
                             size_t valuelen)
{
    const char *eq = ovr ? strchr(ovr, '=') : NULL;
    if (!eq) return CFG_SPLIT_NO_EQUALS;
    if (copy_trimmed(key, keylen, ovr, eq) < 0) return CFG_SPLIT_KEY_TOO_LONG;
    if (copy_trimmed(value, valuelen, eq + 1, eq + strlen(eq)) < 0) return CFG_SPLIT_VALUE_TOO_LONG;
    return CFG_SPLIT_OK;
}
