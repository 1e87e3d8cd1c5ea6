/* replay_rails_csv.c: the parser of the outside replay's rails CSV (see replay_rails_csv.h). */
#include "replay_rails_csv.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cfg_number.h"

int replay_rails_csv_read(FILE *f, const char *name, rail_reading **rails, size_t *n, char *why,
                          size_t why_len)
{
    rail_reading *r = NULL;
    size_t nr = 0, cap = 0;
    char line[REPLAY_RAILS_LINE_MAX + 2];
    long lineno = 0;
    int rc = -1, seen_header = 0;
    *rails = NULL;
    *n = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        size_t len = strlen(line);
        if (len == sizeof line - 1 && line[len - 1] != '\n' && !feof(f)) {
            snprintf(why, why_len, "rails CSV %.300s line %ld: longer than %d bytes", name, lineno,
                     REPLAY_RAILS_LINE_MAX);
            goto out;
        }
        char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        if (*p == '#' || *p == '\n' || *p == '\r' || !*p) continue;
        double v[3];
        const char *q = p;
        int k = 0, bad = 0;
        for (; k < 3 && !bad; k++) {
            if (cfg_number_scan(q, &v[k], &q) != CFG_NUMBER_OK) {
                bad = 1;
                break;
            }
            while (*q == ' ' || *q == '\t') q++;
            if (k < 2 && *q++ != ',') bad = 1;
        }
        if (bad && k == 0 && nr == 0 && !seen_header) { /* a header line */
            seen_header = 1;
            continue;
        }
        while (*q == ' ' || *q == '\t' || *q == '\r' || *q == '\n') q++;
        if (bad || *q) {
            snprintf(why, why_len,
                     "rails CSV %.300s line %ld: expected t_s,compress_mm,shear_mm (three finite numbers)",
                     name, lineno);
            goto out;
        }
        for (int c = 1; c <= 2; c++)
            if (!(fabs(v[c]) <= REPLAY_RAILS_MAX_MM)) {
                snprintf(why, why_len,
                         "rails CSV %.300s line %ld: %s %.6g is beyond any rail (|position| <= %.0e mm, the "
                         "bound of a rig file's soft limits)",
                         name, lineno, c == 1 ? "compress_mm" : "shear_mm", v[c], REPLAY_RAILS_MAX_MM);
                goto out;
            }
        if (nr > 0 && !(v[0] > r[nr - 1].t)) {
            snprintf(why, why_len, "rails CSV %.300s line %ld: t_s must increase (%.9g after %.9g)", name,
                     lineno, v[0], r[nr - 1].t);
            goto out;
        }
        if (nr == cap) {
            size_t nc = cap ? 2 * cap : 1024;
            rail_reading *a = nc <= REPLAY_RAILS_MAX ? realloc(r, nc * sizeof *a) : NULL;
            if (!a) {
                snprintf(why, why_len, "rails CSV %.300s: %s", name,
                         nc > REPLAY_RAILS_MAX ? "too many readings" : "out of memory");
                goto out;
            }
            r = a;
            cap = nc;
        }
        r[nr++] = (rail_reading){v[0], v[1], v[2]};
    }
    if (ferror(f)) {
        snprintf(why, why_len, "rails CSV %.300s: read error", name);
        goto out;
    }
    if (nr < 2) {
        snprintf(why, why_len, "rails CSV %.300s: needs at least two readings (t_s,compress_mm,shear_mm)",
                 name);
        goto out;
    }
    rc = 0;
out:
    if (rc) {
        free(r);
        r = NULL;
        nr = 0;
    }
    *rails = r;
    *n = nr;
    return rc;
}
