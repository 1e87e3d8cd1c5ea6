/* cfg_number.h: the one number grammar of every value that comes from outside (scene and rig
 * files, `--set` overrides, the CLIs' numeric options, the API's overrides, the CSV files read
 * back): plain decimal, nothing else.
 *
 *   number  = [ "+" | "-" ] digits [ "." [ digits ] ] [ exponent ]
 *           | [ "+" | "-" ] "." digits [ exponent ]
 *   exponent = ( "e" | "E" ) [ "+" | "-" ] digits
 *
 * strtod alone also takes hex floats ("0x1p1"), "inf", "nan" and "infinity", and depends on the
 * locale's decimal point; this grammar takes none of them. The value is then converted with
 * strtod (in the "C" locale's sense: only '.' is a decimal point, the span has been checked) and
 * must be finite and, unless zero, normal (a subnormal such as 1e-310 is refused). Nothing here
 * allocates or keeps state. */
#ifndef RIBBON_CONFIG_CFG_NUMBER_H
#define RIBBON_CONFIG_CFG_NUMBER_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Why a text is not a number (cfg_number_scan, cfg_number_parse). */
typedef enum cfg_number_status {
    CFG_NUMBER_OK = 0,
    CFG_NUMBER_NOT_DECIMAL, /* no plain decimal number here (hex, letters, empty) */
    CFG_NUMBER_NOT_FINITE,  /* "inf", "nan", or decimal but too large for a double (1e999) */
    CFG_NUMBER_TRAILING,    /* cfg_number_parse only: a number followed by other text */
    CFG_NUMBER_SUBNORMAL    /* non-zero but below DBL_MIN (1e-310): no value of any key, and
                               arithmetic on it loses its precision (issue 17, item 12) */
} cfg_number_status;

/* Scan one number at s (leading spaces and tabs skipped). On CFG_NUMBER_OK, *out holds it and
 * *end (if not NULL) points just past it; what follows is the caller's to judge. A number
 * followed directly by 'x' or 'X' ("0x1p1") is CFG_NUMBER_NOT_DECIMAL, never 0 followed by text.
 * On failure *out and *end are left alone. */
cfg_number_status cfg_number_scan(const char *s, double *out, const char **end);

/* The whole of s (surrounding spaces and tabs allowed) must be one number. */
cfg_number_status cfg_number_parse(const char *s, double *out);

/* strtod's shape for call sites written around it: the number at s by cfg_number_scan, *end
 * just past it; when there is no plain decimal finite number there, returns 0 with *end = s (as
 * strtod does when it converts nothing), so "end == s" is the caller's refusal. */
double cfg_number_strtod(const char *s, char **end);

/* Split "A:B:N" (a range of N points, N a decimal integer in [1, n_max]) into *a, *b, *n; both
 * numbers by this grammar. 0 on success, -2 for a range written high to low (A > B: refused, not
 * sorted, so a grid never runs backwards; issue 33), -1 otherwise. */
int cfg_number_range(const char *s, double *a, double *b, int *n, int n_max);

/* A short phrase for a status, e.g. "is not a plain decimal number". */
const char *cfg_number_why(cfg_number_status st);

#ifdef __cplusplus
}
#endif

#endif
