/* cfg_datetime.c: ISO 8601 date-times with a zone, to seconds since the epoch (cfg_datetime.h).
 * The calendar arithmetic is the proleptic Gregorian days-from-civil count (H. Hinnant's
 * algorithm), so no timegm, no TZ variable and no locale are involved. */
#include "cfg_datetime.h"

#include <stdio.h>
#include <string.h>

/* n decimal digits at *p into *v; advances *p. 0 on success. */
static int digits(const char **p, int n, int *v)
{
    int x = 0;
    for (int i = 0; i < n; i++) {
        char c = (*p)[i];
        if (c < '0' || c > '9') return -1;
        x = 10 * x + (c - '0');
    }
    *p += n;
    *v = x;
    return 0;
}

/* Days since 1970-01-01 of a proleptic Gregorian date. */
static long days_from_civil(long y, int m, int d)
{
    y -= m <= 2;
    long era = (y >= 0 ? y : y - 399) / 400;
    long yoe = y - era * 400;
    long doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    long doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    return era * 146097 + doe - 719468;
}

static int month_days(int y, int m)
{
    static const int n[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    int leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    return m == 2 && leap ? 29 : n[m - 1];
}

static cfg_datetime_status bad(cfg_datetime_status st, char *why, size_t why_len, const char *text)
{
    if (why && why_len) snprintf(why, why_len, "%s", text);
    return st;
}

cfg_datetime_status cfg_datetime_parse(const char *s, double *epoch_s, char *why, size_t why_len)
{
    const char *p = s;
    int y, mo, d, h, mi, sec = 0;
    double frac = 0.0;
    const char *form = "expected YYYY-MM-DDThh:mm[:ss[.fff]] with Z or an offset such as +01:00";
    if (digits(&p, 4, &y) || *p++ != '-' || digits(&p, 2, &mo) || *p++ != '-' || digits(&p, 2, &d))
        return bad(CFG_DATETIME_SYNTAX, why, why_len, form);
    if (*p == '\0')
        return bad(CFG_DATETIME_SYNTAX, why, why_len, "a date without a time of day; add Thh:mm and a zone (Z or +hh:mm)");
    if (*p != 'T' && *p != ' ') return bad(CFG_DATETIME_SYNTAX, why, why_len, form);
    p++;
    if (digits(&p, 2, &h) || *p++ != ':' || digits(&p, 2, &mi)) return bad(CFG_DATETIME_SYNTAX, why, why_len, form);
    if (*p == ':') {
        p++;
        if (digits(&p, 2, &sec)) return bad(CFG_DATETIME_SYNTAX, why, why_len, form);
        if (*p == '.') {
            p++;
            double scale = 0.1;
            if (*p < '0' || *p > '9') return bad(CFG_DATETIME_SYNTAX, why, why_len, form);
            for (int n = 0; *p >= '0' && *p <= '9'; p++, n++) {
                if (n >= 9) return bad(CFG_DATETIME_SYNTAX, why, why_len, "more than 9 digits of a second");
                frac += scale * (*p - '0');
                scale *= 0.1;
            }
        }
    }
    if (mo < 1 || mo > 12 || d < 1 || d > month_days(y, mo) || h > 23 || mi > 59 || sec > 59)
        return bad(CFG_DATETIME_RANGE, why, why_len, "a field is out of range (month, day of the month, hour, minute or second)");
    int offset_min = 0;
    if (*p == 'Z') {
        p++;
    } else if (*p == '+' || *p == '-') {
        int sign = *p++ == '-' ? -1 : 1, oh, om;
        if (digits(&p, 2, &oh) || *p++ != ':' || digits(&p, 2, &om)) return bad(CFG_DATETIME_SYNTAX, why, why_len, form);
        if (oh > 23 || om > 59) return bad(CFG_DATETIME_RANGE, why, why_len, "the zone offset is out of range");
        offset_min = sign * (60 * oh + om);
    } else if (*p == '\0') {
        return bad(CFG_DATETIME_NO_ZONE, why, why_len,
                   "no time zone: add Z (UTC) or the offset from UTC, such as +01:00");
    } else {
        return bad(CFG_DATETIME_SYNTAX, why, why_len, form);
    }
    if (*p != '\0') return bad(CFG_DATETIME_SYNTAX, why, why_len, "text after the date-time");
    double t = (double)days_from_civil(y, mo, d) * 86400.0 + 3600.0 * h + 60.0 * mi + sec + frac;
    *epoch_s = t - 60.0 * offset_min;
    return CFG_DATETIME_OK;
}
