/* cfg_number.c: the plain-decimal number grammar shared by every reader of outside numbers (see
 * cfg_number.h). The span is checked by hand first, then converted by strtod, so strtod's
 * extensions (hex floats, inf, nan) never get a chance. */
#include "cfg_number.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static int is_digit(char c) { return c >= '0' && c <= '9'; }

/* Length of the decimal number at p, or 0 when there is none. */
static size_t decimal_span(const char *p)
{
    size_t i = 0, mant = 0;
    if (p[i] == '+' || p[i] == '-') i++;
    while (is_digit(p[i])) i++, mant++;
    if (p[i] == '.') {
        i++;
        while (is_digit(p[i])) i++, mant++;
    }
    if (mant == 0) return 0;
    if (p[i] == 'e' || p[i] == 'E') {
        size_t j = i + 1;
        if (p[j] == '+' || p[j] == '-') j++;
        if (!is_digit(p[j])) return 0; /* "1e", "1e+": not a number */
        while (is_digit(p[j])) j++;
        i = j;
    }
    return i;
}

cfg_number_status cfg_number_scan(const char *s, double *out, const char **end)
{
    if (!s) return CFG_NUMBER_NOT_DECIMAL;
    while (*s == ' ' || *s == '\t') s++;
    size_t n = decimal_span(s);
    if (n == 0) {
        /* strtod's words for the non-finite: named as such, never converted. */
        const char *w = s + (*s == '+' || *s == '-');
        if (!strncasecmp(w, "inf", 3) || !strncasecmp(w, "nan", 3)) return CFG_NUMBER_NOT_FINITE;
        return CFG_NUMBER_NOT_DECIMAL;
    }
    /* "0x1p1": a hex float, never 0 followed by text. */
    if (s[n] == 'x' || s[n] == 'X') return CFG_NUMBER_NOT_DECIMAL;
    char buf[128];
    double v;
    if (n < sizeof buf) {
        memcpy(buf, s, n);
        buf[n] = '\0';
        v = strtod(buf, NULL);
    } else {
        char *heap = malloc(n + 1);
        if (!heap) return CFG_NUMBER_NOT_DECIMAL;
        memcpy(heap, s, n);
        heap[n] = '\0';
        v = strtod(heap, NULL);
        free(heap);
    }
    if (!isfinite(v)) return CFG_NUMBER_NOT_FINITE;
    if (v != 0.0 && fabs(v) < DBL_MIN) return CFG_NUMBER_SUBNORMAL;
    *out = v;
    if (end) *end = s + n;
    return CFG_NUMBER_OK;
}

cfg_number_status cfg_number_parse(const char *s, double *out)
{
    const char *end;
    double v;
    cfg_number_status st = cfg_number_scan(s, &v, &end);
    if (st) return st;
    while (*end == ' ' || *end == '\t') end++;
    if (*end) return CFG_NUMBER_TRAILING;
    *out = v;
    return CFG_NUMBER_OK;
}

double cfg_number_strtod(const char *s, char **end)
{
    const char *e;
    double v;
    if (cfg_number_scan(s, &v, &e) != CFG_NUMBER_OK) {
        if (end) *end = (char *)s; /* strtod's own convention: no conversion */
        return 0.0;
    }
    if (end) *end = (char *)e;
    return v;
}

int cfg_number_range(const char *s, double *a, double *b, int *n, int n_max)
{
    const char *p;
    double x, y, k;
    if (!s || cfg_number_scan(s, &x, &p) || *p++ != ':') return -1;
    if (cfg_number_scan(p, &y, &p) || *p++ != ':') return -1;
    for (const char *q = p; *q; q++)
        if (*q < '0' || *q > '9') return -1; /* N: digits only */
    if (!*p || strlen(p) > 9 || cfg_number_parse(p, &k)) return -1;
    if (k < 1 || k > n_max) return -1;
    if (x > y) return -2; /* high to low: the callers' grids and brackets assume A <= B */
    *a = x;
    *b = y;
    *n = (int)k;
    return 0;
}

const char *cfg_number_why(cfg_number_status st)
{
    switch (st) {
    case CFG_NUMBER_OK: return "is a number";
    case CFG_NUMBER_NOT_DECIMAL: return "is not a number (plain decimal only, no hex)";
    case CFG_NUMBER_NOT_FINITE: return "is not a finite number (plain decimal only)";
    case CFG_NUMBER_TRAILING: return "has text after the number";
    case CFG_NUMBER_SUBNORMAL: return "is too small to compute with (a subnormal double, below 2.2e-308)";
    }
    return "is not a number";
}
