/* grbl_proto.c: GRBL 1.1 line classification, status report parsing and code texts.
 * Code meanings follow GRBL 1.1's published error and alarm code tables (the project's
 * doc/csv/error_codes_en_US.csv and alarm_codes_en_US.csv); texts are ours, shortened.
 * Parsing never reads past len and never trusts a terminator. */
#include "grbl_proto.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const state_names[GRBL_STATE_COUNT] = {
    "Idle", "Run", "Hold", "Jog", "Alarm", "Door", "Check", "Home", "Sleep",
};

const char *grbl_state_name(grbl_state s)
{
    return ((int)s >= 0 && s < GRBL_STATE_COUNT) ? state_names[s] : "unknown";
}

const char *grbl_error_text(int code)
{
    switch (code) {
    case 1: return "G-code word without a letter";
    case 2: return "bad or missing number in a G-code word";
    case 3: return "unrecognised or unsupported $ system command";
    case 4: return "negative value where a positive one is expected";
    case 5: return "homing cycle is not enabled in the settings";
    case 6: return "step pulse time below the 3 microsecond minimum";
    case 7: return "EEPROM read failed; settings restored to defaults";
    case 8: return "$ command needs the controller idle";
    case 9: return "G-code locked out during alarm or jog";
    case 10: return "soft limits need homing enabled";
    case 11: return "line too long; dropped";
    case 12: return "step rate would exceed the controller's maximum";
    case 13: return "safety door open";
    case 14: return "build info or startup line too long for EEPROM";
    case 15: return "jog target exceeds machine travel; jog ignored";
    case 16: return "jog command malformed (needs '=' and an axis word, no forbidden G-code)";
    case 17: return "laser mode needs PWM output";
    case 20: return "unsupported or invalid G-code command";
    case 21: return "more than one command of a modal group in a block";
    case 22: return "feed rate not set";
    case 23: return "command needs an integer value";
    case 24: return "two commands in a block need axis words";
    case 25: return "a G-code word repeated in a block";
    case 26: return "no axis words where the command needs them";
    case 27: return "line number out of range";
    case 28: return "a required value word is missing";
    case 29: return "work coordinate systems G59.1-3 not supported";
    case 30: return "G53 only with G0 or G1";
    case 31: return "axis words where no command uses them";
    case 32: return "arc without axis words in the selected plane";
    case 33: return "motion target invalid";
    case 34: return "arc radius definition error";
    case 35: return "arc without offset words in the selected plane";
    case 36: return "unused value words in the block";
    case 37: return "tool length offset not on the configured axis";
    case 38: return "tool number above the supported maximum";
    default: return "unknown GRBL error";
    }
}

const char *grbl_alarm_text(int code)
{
    /* GRBL 1.1's alarm table (alarm_codes_en_US.csv): its name, then its meaning shortened. */
    switch (code) {
    case 1: return "Hard limit: a limit switch halted the machine; position likely lost, re-home";
    case 2: return "Soft limit: motion target beyond machine travel; position retained, unlock";
    case 3: return "Abort during cycle: reset while in motion; position likely lost, re-home";
    case 4: return "Probe fail: probe not in the expected initial state";
    case 5: return "Probe fail: no contact within the programmed travel";
    case 6: return "Homing fail: the homing cycle was reset";
    case 7: return "Homing fail: safety door opened during homing";
    case 8: return "Homing fail: pull-off did not clear the limit switch";
    case 9: return "Homing fail: limit switch not found within the search distance";
    default: return "unknown GRBL alarm";
    }
}

static bool starts(const char *s, size_t len, const char *pfx)
{
    size_t k = strlen(pfx);
    return len >= k && memcmp(s, pfx, k) == 0;
}

/* Parse a small non-negative decimal integer from s[0..len); -1 if not one. */
static int small_int(const char *s, size_t len)
{
    if (len == 0 || len > 4)
        return -1;
    int v = 0;
    for (size_t i = 0; i < len; i++) {
        if (s[i] < '0' || s[i] > '9')
            return -1;
        v = v * 10 + (s[i] - '0');
    }
    return v;
}

grbl_line_kind grbl_line_classify(const char *line, size_t len, int *code)
{
    *code = 0;
    while (len > 0 && (line[len - 1] == '\r' || line[len - 1] == '\n' || line[len - 1] == ' '))
        len--;
    if (len == 0)
        return GRBL_LINE_EMPTY;
    if (len == 2 && memcmp(line, "ok", 2) == 0)
        return GRBL_LINE_OK;
    if (starts(line, len, "error:")) {
        int c = small_int(line + 6, len - 6);
        *code = c < 0 ? -1 : c;
        return GRBL_LINE_ERROR;
    }
    if (starts(line, len, "ALARM:")) {
        int c = small_int(line + 6, len - 6);
        *code = c < 0 ? -1 : c;
        return GRBL_LINE_ALARM;
    }
    if (line[0] == '<')
        return GRBL_LINE_STATUS;
    if (starts(line, len, "Grbl "))
        return GRBL_LINE_WELCOME;
    if (line[0] == '[')
        return GRBL_LINE_MESSAGE;
    return GRBL_LINE_OTHER;
}

static bool say(char *why, size_t why_len, const char *fmt, size_t at, const char *what)
{
    if (why && why_len)
        snprintf(why, why_len, fmt, at, what);
    return false;
}

/* Parse up to max comma-separated numbers from s[0..len); returns count, -1 on a bad number. */
static int parse_numbers(const char *s, size_t len, double *v, int max, size_t *bad_at)
{
    char buf[32];
    int k = 0;
    size_t i = 0;
    while (i <= len && k < max + 1) {
        size_t j = i;
        while (j < len && s[j] != ',')
            j++;
        size_t w = j - i;
        if (w == 0 || w >= sizeof buf) {
            *bad_at = i;
            return -1;
        }
        memcpy(buf, s + i, w);
        buf[w] = 0;
        char *end = NULL;
        double x = strtod(buf, &end);
        if (end != buf + w || x != x || x > 1e9 || x < -1e9) {
            *bad_at = i;
            return -1;
        }
        if (k < max)
            v[k] = x;
        k++;
        i = j + 1;
        if (j >= len)
            break;
    }
    if (k > max) {
        *bad_at = len;
        return -1;
    }
    return k;
}

bool grbl_status_parse(const char *line, size_t len, grbl_report *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    out->substate = -1;
    out->buffer_blocks = -1;
    while (len > 0 && (line[len - 1] == '\r' || line[len - 1] == '\n'))
        len--;
    if (len < 2 || line[0] != '<')
        return say(why, why_len, "status report: expected '<' at byte %zu%s", 0, "");
    if (line[len - 1] != '>')
        return say(why, why_len, "status report truncated: no closing '>' (length %zu)%s", len, "");
    const char *s = line + 1;
    size_t L = len - 2;
    /* State field. */
    size_t i = 0;
    while (i < L && s[i] != '|' && s[i] != ':')
        i++;
    static const char *const names[] = {"Idle", "Run", "Hold", "Jog", "Alarm", "Door", "Check", "Home", "Sleep"};
    int st = -1;
    for (int k = 0; k < GRBL_STATE_COUNT; k++)
        if (strlen(names[k]) == i && memcmp(s, names[k], i) == 0)
            st = k;
    if (st < 0)
        return say(why, why_len, "status report: unknown state at byte %zu%s", 1, "");
    out->state = (grbl_state)st;
    if (i < L && s[i] == ':') {
        size_t j = i + 1;
        while (j < L && s[j] != '|')
            j++;
        out->substate = small_int(s + i + 1, j - i - 1);
        if (out->substate < 0)
            return say(why, why_len, "status report: bad substate at byte %zu%s", i + 2, "");
        i = j;
    }
    double wpos[GRBL_MAX_AXES] = {0}, wco[GRBL_MAX_AXES] = {0};
    bool have_m = false, have_w = false, have_wco = false;
    int nax = 0;
    /* Fields, each "Name:values", separated by '|'. Capped by the line length. */
    for (int guard = 0; i < L && guard < 64; guard++) {
        if (s[i] != '|')
            return say(why, why_len, "status report: expected '|' at byte %zu%s", i + 1, "");
        size_t a = i + 1, b = a;
        while (b < L && s[b] != '|')
            b++;
        size_t c = a;
        while (c < b && s[c] != ':')
            c++;
        const char *name = s + a;
        size_t nl = c - a;
        const char *val = s + c + 1;
        size_t vl = c < b ? b - c - 1 : 0;
        size_t bad = 0;
        double v[GRBL_MAX_AXES + 1];
        if ((nl == 4 && memcmp(name, "MPos", 4) == 0) || (nl == 4 && memcmp(name, "WPos", 4) == 0) ||
            (nl == 3 && memcmp(name, "WCO", 3) == 0)) {
            if (c >= b)
                return say(why, why_len, "status report: field without ':' at byte %zu%s", a + 1, "");
            int k = parse_numbers(val, vl, v, GRBL_MAX_AXES, &bad);
            if (k < 1)
                return say(why, why_len, "status report: bad position number at byte %zu%s", c + 2 + bad, "");
            double *dst = name[0] == 'M' ? out->pos : name[0] == 'W' && nl == 4 ? wpos : wco;
            for (int q = 0; q < k; q++)
                dst[q] = v[q];
            if (name[0] == 'M' || (name[0] == 'W' && nl == 4))
                nax = k;
            if (name[0] == 'M')
                have_m = true;
            else if (nl == 4)
                have_w = true;
            else
                have_wco = true;
        } else if ((nl == 2 && memcmp(name, "FS", 2) == 0) || (nl == 1 && name[0] == 'F')) {
            int k = parse_numbers(val, vl, v, 2, &bad);
            if (k < 1 || v[0] < 0.0)
                return say(why, why_len, "status report: bad feed number at byte %zu%s", c + 2 + bad, "");
            out->feed_mm_min = v[0];
        } else if (nl == 2 && memcmp(name, "Bf", 2) == 0) {
            int k = parse_numbers(val, vl, v, 2, &bad);
            if (k < 1)
                return say(why, why_len, "status report: bad buffer field at byte %zu%s", c + 2 + bad, "");
            out->buffer_blocks = (int)v[0];
        } else if (nl == 0) {
            return say(why, why_len, "status report: empty field at byte %zu%s", a + 1, "");
        }
        /* Other fields (Ln, Pn, Ov, A) are not needed here and skipped. */
        i = b;
    }
    out->have_wco = have_wco;
    if (have_wco)
        memcpy(out->wco, wco, sizeof wco);
    if (have_m) {
        out->have_pos = true;
    } else if (have_w) {
        for (int q = 0; q < GRBL_MAX_AXES; q++)
            out->pos[q] = wpos[q] + (have_wco ? wco[q] : 0.0);
        out->have_pos = true;
        out->work_pos = true;
    } else {
        return say(why, why_len, "status report without MPos or WPos (length %zu)%s", len, "");
    }
    out->n_axes = nax;
    return true;
}
