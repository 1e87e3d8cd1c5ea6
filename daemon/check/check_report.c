/* check_report.c: the readiness report: a bounded list of ok / warn / fail lines, printed one per
 * line for people and as JSON for the API and scripts. A report that runs out of room ends with
 * a fail saying so: a check that could not be listed must not read as passed. */
#include <stdarg.h>
#include <string.h>

#include "check.h"

void check_report_init(check_report *r)
{
    memset(r, 0, sizeof *r);
}

const char *check_level_name(check_level l)
{
    return l == CHECK_OK ? "ok" : l == CHECK_WARN ? "warn" : "fail";
}

void check_add(check_report *r, check_level l, const char *part, const char *what, const char *fmt, ...)
{
    if (r->n >= CHECK_MAX_ITEMS) {
        if (l == CHECK_FAIL) r->fails++;
        return;
    }
    check_item *it = &r->items[r->n++];
    if (r->n == CHECK_MAX_ITEMS) { /* the last slot says the list was cut */
        it->level = CHECK_FAIL;
        snprintf(it->part, sizeof it->part, "check");
        snprintf(it->what, sizeof it->what, "report");
        snprintf(it->text, sizeof it->text, "more than %d checks: the rest were not listed", CHECK_MAX_ITEMS - 1);
        r->fails++;
        if (l == CHECK_FAIL) r->fails++;
        return;
    }
    it->level = l;
    snprintf(it->part, sizeof it->part, "%s", part);
    snprintf(it->what, sizeof it->what, "%s", what);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(it->text, sizeof it->text, fmt, ap);
    va_end(ap);
    if (l == CHECK_FAIL) r->fails++;
    if (l == CHECK_WARN) r->warns++;
}

void check_report_print(const check_report *r, FILE *f)
{
    for (int i = 0; i < r->n; i++) {
        const check_item *it = &r->items[i];
        fprintf(f, "%-4s  %-14s %-9s %s\n", check_level_name(it->level), it->part, it->what, it->text);
    }
    if (r->fails)
        fprintf(f, "NOT READY: %d fail%s, %d warning%s\n", r->fails, r->fails == 1 ? "" : "s", r->warns,
                r->warns == 1 ? "" : "s");
    else
        fprintf(f, "ready: %d checks, %d warning%s\n", r->n, r->warns, r->warns == 1 ? "" : "s");
}

json_t *check_report_json(const check_report *r)
{
    json_t *a = json_array();
    for (int i = 0; i < r->n; i++) {
        const check_item *it = &r->items[i];
        json_array_append_new(a, json_pack("{s:s, s:s, s:s, s:s}", "level", check_level_name(it->level), "part",
                                           it->part, "what", it->what, "text", it->text));
    }
    return json_pack("{s:b, s:i, s:i, s:o}", "ok", r->fails == 0, "fails", r->fails, "warns", r->warns, "checks", a);
}
