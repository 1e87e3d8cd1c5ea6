/* sim_sweep_origin.c: the line that says what made a sweep file (see sim_sweep_origin.h). */
#include "sim_sweep_origin.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim_sweep_row.h"

static uint64_t fnv(const char *s)
{
    uint64_t h = 1469598103934665603ull;
    for (; *s; s++) {
        h ^= (unsigned char)*s;
        h *= 1099511628211ull;
    }
    return h;
}

void sweep_origin_format(const sweep_spec *sp, double pa, double pb, int np, double ga, double gb, int ng, double da,
                         double db, int nd, char *out, size_t out_len)
{
    const rod_scene *sc = &sp->base;
    char buf[1024];
    /* Every field the points share, exactly; the ones the grid sets are left out, and N, which
     * has its own field. */
    snprintf(buf, sizeof buf, "%a %a %a %a %a %a %a %a %a|%a %a|%a %a %d|%a %a %a %d|%a %a", sc->length, sc->width,
             sc->thickness, sc->youngs_modulus, sc->shear_modulus, sc->density, sc->gravity[0], sc->gravity[1],
             sc->gravity[2], sp->sign, sc->fold_stiffness_factor, sc->shear_rate, sc->shear_max,
             (int)sc->route, sc->dt, sc->damping, sc->tolerance, sc->max_iterations, sc->snap_speed,
             sc->asym_threshold);
    snprintf(out, out_len,
             "ribbon-sim %s; scene %016llx; nodes %d; phi %.15g:%.15g:%d; gamma %.15g:%.15g:%d; dl %.15g:%.15g:%d; "
             "gamma-tol %.15g; seed %s",
             RIBBON_VERSION, (unsigned long long)fnv(buf), sc->nodes, pa, pb, np, ga, gb, ng, da, db, nd, sp->gamma_tol,
             sp->seed_route ? "route" : "continue");
}

/* The field of line named key ("nodes"): its value, up to "; " or the end, into val. 1 found. */
static int field(const char *line, const char *key, char *val, size_t len)
{
    size_t kl = strlen(key);
    for (const char *p = line; p && *p;) {
        if (!strncmp(p, key, kl) && p[kl] == ' ') {
            const char *v = p + kl + 1, *e = strstr(v, "; ");
            size_t n = e ? (size_t)(e - v) : strlen(v);
            snprintf(val, len, "%.*s", (int)(n < len ? n : len - 1), v);
            return 1;
        }
        p = strstr(p, "; ");
        if (p) p += 2;
    }
    return 0;
}

static const char *const keys[] = {"ribbon-sim", "scene", "nodes", "phi", "gamma", "dl", "gamma-tol", "seed"};
#define NKEYS (sizeof keys / sizeof keys[0])

/* Compares field k of a and b: 0 same, else -1 with what. */
static int compare_field(const char *a, const char *b, const char *k, char *what, size_t what_len)
{
    char va[160] = "", vb[160] = "";
    int ha = field(a, k, va, sizeof va), hb = field(b, k, vb, sizeof vb);
    if (ha && hb && !strcmp(va, vb)) return 0;
    snprintf(what, what_len, "%s %s against %s %s", k, ha ? va : "(none)", k, hb ? vb : "(none)");
    return -1;
}

int sweep_origin_compare(const char *a, const char *b, char *what, size_t what_len)
{
    for (size_t k = 0; k < NKEYS; k++)
        if (compare_field(a, b, keys[k], what, what_len)) return -1;
    return 0;
}

/* "A:B:n" into the grid's points; 0 or -1. */
static int grid_of(const char *v, double *a, double *b, int *n)
{
    char tail;
    return sscanf(v, "%lf:%lf:%d%c", a, b, n, &tail) == 3 && *n >= 1 ? 0 : -1;
}

static double point(double a, double b, int n, int i) { return n == 1 ? a : a + (b - a) * i / (n - 1); }

/* Every point of the run's axis k is one of the file's. */
static int on_file_axis(const char *file, const char *run, const char *k, char *what, size_t what_len)
{
    char vf[160], vr[160];
    double fa, fb, ra, rb;
    int fn, rn;
    if (!field(file, k, vf, sizeof vf) || !field(run, k, vr, sizeof vr) || grid_of(vf, &fa, &fb, &fn) ||
        grid_of(vr, &ra, &rb, &rn))
        return compare_field(file, run, k, what, what_len);
    for (int i = 0; i < rn; i++) {
        double x = point(ra, rb, rn, i);
        int found = 0;
        for (int j = 0; j < fn && !found; j++) found = fabs(x - point(fa, fb, fn, j)) <= 1e-9 * fmax(1.0, fabs(x));
        if (!found) {
            snprintf(what, what_len, "%s %.15g is not on the file's %s grid %s", k, x, k, vf);
            return -1;
        }
    }
    return 0;
}

int sweep_origin_resumable(const char *file, const char *run, char *what, size_t what_len)
{
    for (size_t k = 0; k < NKEYS; k++) {
        int bad = !strcmp(keys[k], "phi") || !strcmp(keys[k], "dl") ? on_file_axis(file, run, keys[k], what, what_len)
                                                                    : compare_field(file, run, keys[k], what, what_len);
        if (bad) return -1;
    }
    return 0;
}
