/* grbl_settings.c: `$$` lines parsed into a table, and the driver's check of them (see
 * grbl_settings.h). Refuse what would make positions or speeds wrong without anyone noticing
 * (inches, a rate limit below the rig's speeds: GRBL clamps a jog's feed silently), adopt what
 * the controller knows better than the rig file (its acceleration), warn on the rest. */
#include "grbl_settings.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bool grbl_setting_line_parse(const char *line, size_t len, int *num, double *val)
{
    char buf[48];
    while (len > 0 && (line[len - 1] == '\r' || line[len - 1] == '\n' || line[len - 1] == ' '))
        len--;
    if (len < 4 || len >= sizeof buf || line[0] != '$')
        return false;
    memcpy(buf, line, len);
    buf[len] = 0;
    size_t i = 1;
    int n = 0;
    for (; i < len && buf[i] >= '0' && buf[i] <= '9'; i++) {
        if (i > 4)
            return false;
        n = n * 10 + (buf[i] - '0');
    }
    if (i == 1 || i >= len || buf[i] != '=')
        return false;
    char *end = NULL;
    double x = strtod(buf + i + 1, &end);
    if (end == buf + i + 1 || *end || !isfinite(x))
        return false;
    *num = n;
    *val = x;
    return true;
}

void grbl_settings_set(grbl_settings *s, int num, double val)
{
    if (num < 0 || num >= GRBL_SETTING_MAX)
        return;
    if (!s->have[num])
        s->count++;
    s->have[num] = true;
    s->v[num] = val;
}

size_t grbl_settings_format(const grbl_settings *s, char *buf, size_t n)
{
    size_t used = 0;
    if (n)
        buf[0] = 0;
    for (int i = 0; i < GRBL_SETTING_MAX && n; i++) {
        if (!s->have[i])
            continue;
        int k = snprintf(buf + used, n - used, "%s$%d=%g", used ? " " : "", i, s->v[i]);
        if (k < 0 || (size_t)k >= n - used) {
            buf[used] = 0;
            break;
        }
        used += (size_t)k;
    }
    return used;
}

static void add(char *dst, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void add(char *dst, size_t n, const char *fmt, ...)
{
    size_t used = strlen(dst);
    if (used + 3 >= n)
        return;
    if (used) {
        memcpy(dst + used, "; ", 3);
        used += 2;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(dst + used, n - used, fmt, ap);
    va_end(ap);
}

static bool need(const grbl_settings *s, const char *rail, int num, const char *what,
                 grbl_settings_check_out *out)
{
    if (s->have[num])
        return true;
    out->refuse = true;
    snprintf(out->refuse_why, sizeof out->refuse_why,
             "rail '%s': the controller's `$$` lists no $%d (%s): is it GRBL 1.1?", rail, num, what);
    return false;
}

void grbl_settings_check(const grbl_settings *s, int axis, const rail_params *p,
                         grbl_settings_check_out *out)
{
    memset(out, 0, sizeof *out);
    out->accel_mm_s2 = p->accel_mm_s2;
    const char *rn = p->name;
    char ax = (char)('X' + axis);
    int rate = 110 + axis, acc = 120 + axis, trav = 130 + axis;
    if (!need(s, rn, 13, "report inches", out) || !need(s, rn, 10, "status report mask", out) ||
        !need(s, rn, rate, "max rate", out) || !need(s, rn, acc, "acceleration", out))
        return;
    if (s->v[13] != 0.0) {
        out->refuse = true;
        snprintf(out->refuse_why, sizeof out->refuse_why,
                 "rail '%s': the controller reports positions in inches ($13=%g) and the driver "
                 "reads millimetres: set $13=0",
                 rn, s->v[13]);
        return;
    }
    double rate_mm_min = s->v[rate];
    if (rate_mm_min + 1e-9 < p->max_speed_mm_s * 60.0) {
        out->refuse = true;
        snprintf(out->refuse_why, sizeof out->refuse_why,
                 "rail '%s': max_speed_mm_s = %g mm/s (%g mm/min) exceeds the controller's axis %c "
                 "max rate $%d=%g mm/min, which would clamp every jog's feed without a word: set "
                 "$%d=%g or more, or max_speed_mm_s = %g or less",
                 rn, p->max_speed_mm_s, p->max_speed_mm_s * 60.0, ax, rate, rate_mm_min, rate,
                 p->max_speed_mm_s * 60.0, rate_mm_min / 60.0);
        return;
    }
    double a = s->v[acc];
    if (!(a > 0.0)) {
        out->refuse = true;
        snprintf(out->refuse_why, sizeof out->refuse_why,
                 "rail '%s': the controller's axis %c acceleration $%d=%g is not positive", rn, ax, acc, a);
        return;
    }
    if (fabs(a - p->accel_mm_s2) > 0.01 * p->accel_mm_s2) {
        out->accel_mm_s2 = a;
        add(out->warn, sizeof out->warn,
            "accel_mm_s2 = %g mm/s^2 but the controller's $%d=%g mm/s^2: using $%d for stop "
            "distances and the reconstruction",
            p->accel_mm_s2, acc, a, acc);
    }
    if (((int)s->v[10] & 1) == 0) {
        out->work_pos = true;
        add(out->warn, sizeof out->warn,
            "$10=%g reports work positions (WPos): machine positions are WPos + the last WCO; "
            "$10=1 reports them directly",
            s->v[10]);
    }
    if (s->have[22] && s->v[22] != 0.0)
        out->homing = true;
    if (!s->have[20] || s->v[20] == 0.0) {
        add(out->warn, sizeof out->warn,
            "soft limits off ($20=0): only the driver's soft limits [%g, %g] mm guard the travel",
            p->soft_min_mm, p->soft_max_mm);
    } else if (s->have[trav] && s->v[trav] + 1e-9 < p->soft_max_mm - p->soft_min_mm) {
        add(out->warn, sizeof out->warn,
            "the controller's travel $%d=%g mm is shorter than the rail's soft range %g mm: its "
            "soft limit (ALARM:2) may stop a move the rig file allows",
            trav, s->v[trav], p->soft_max_mm - p->soft_min_mm);
    }
    if (!s->have[21] || s->v[21] == 0.0)
        add(out->warn, sizeof out->warn, "hard limits off ($21=0): a limit switch does not stop the controller");
}
