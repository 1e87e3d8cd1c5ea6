/* campaign_predicted.c: the predicted boundary Gamma*(phi): ribbon-sim boundary's CSV, a trace
 * of the scene (rod_boundary_start, then rod_boundary_move down and up in phi from the scene's own
 * phi, as `ribbon-sim boundary --phi A:B` does), its cache file, and interpolation in phi
 * (campaign_predicted.h). */
#include "campaign_predicted.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "rod_boundary.h"

void campaign_predicted_free(campaign_predicted *p)
{
    if (!p) return;
    free(p->phi_deg);
    free(p->gamma);
    p->phi_deg = p->gamma = NULL;
    p->n = 0;
}

static char *slurp(const char *path)
{
    FILE *f = path ? fopen(path, "rb") : NULL;
    if (!f) return NULL;
    size_t cap = 4096, n = 0, r;
    char *s = malloc(cap);
    while (s && (r = fread(s + n, 1, cap - n - 1, f)) > 0) {
        n += r;
        if (n + 1 == cap) {
            char *t = realloc(s, cap *= 2);
            if (!t) free(s);
            s = t;
        }
    }
    fclose(f);
    if (s) s[n] = '\0';
    return s;
}

char *campaign_predicted_key_text(const char *rig_path, const char *scene_path)
{
    char *rig = slurp(rig_path), *scene = slurp(scene_path);
    size_t len = (rig ? strlen(rig) : 0) + (scene ? strlen(scene) : 0) + 8;
    char *key = malloc(len);
    if (key) snprintf(key, len, "%s\n--\n%s", rig ? rig : "", scene ? scene : "");
    free(rig), free(scene);
    return key;
}

uint64_t campaign_predicted_key(const char *text)
{
    uint64_t h = 1469598103934665603ULL;
    for (const unsigned char *s = (const unsigned char *)text; s && *s; s++) {
        h ^= *s;
        h *= 1099511628211ULL;
    }
    return h;
}

static int push(campaign_predicted *p, size_t *cap, double phi, double g)
{
    if (p->n == *cap) {
        size_t nc = *cap ? 2 * *cap : 64;
        double *a = realloc(p->phi_deg, nc * sizeof *a);
        if (!a) return -1;
        p->phi_deg = a;
        double *b = realloc(p->gamma, nc * sizeof *b);
        if (!b) return -1;
        p->gamma = b;
        *cap = nc;
    }
    p->phi_deg[p->n] = phi;
    p->gamma[p->n] = g;
    p->n++;
    return 0;
}

/* Sorts by phi and drops repeats (the trace's start appears once per direction). */
static void sort_unique(campaign_predicted *p)
{
    for (size_t i = 1; i < p->n; i++)
        for (size_t j = i; j > 0 && p->phi_deg[j - 1] > p->phi_deg[j]; j--) {
            double t = p->phi_deg[j]; p->phi_deg[j] = p->phi_deg[j - 1]; p->phi_deg[j - 1] = t;
            t = p->gamma[j]; p->gamma[j] = p->gamma[j - 1]; p->gamma[j - 1] = t;
        }
    size_t m = 0;
    for (size_t i = 0; i < p->n; i++) {
        if (m && fabs(p->phi_deg[i] - p->phi_deg[m - 1]) < 1e-9) continue;
        p->phi_deg[m] = p->phi_deg[i];
        p->gamma[m] = p->gamma[i];
        m++;
    }
    p->n = m;
}

int campaign_predicted_load_csv(const char *path, campaign_predicted *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(why, why_len, "predicted boundary %s: cannot read it", path);
        return -1;
    }
    char line[1024];
    size_t cap = 0;
    int lineno = 0, header = 0, have_dl = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        if (!strncmp(line, "# stop: ", 8)) {
            snprintf(out->stop, sizeof out->stop, "%.299s", line + 8);
            out->stop[strcspn(out->stop, "\n")] = '\0';
        }
        if (line[0] == '#' || line[0] == '\n') continue;
        if (!header) {
            if (strncmp(line, "kind,dl,phi_deg,gamma", 21)) {
                snprintf(why, why_len, "predicted boundary %s line %d: not ribbon-sim boundary's CSV (header "
                         "kind,dl,phi_deg,gamma,...)", path, lineno);
                goto fail;
            }
            header = 1;
            continue;
        }
        if (strncmp(line, "boundary,", 9)) continue; /* saddle-node / pitchfork rows */
        double dl, phi, g;
        if (sscanf(line + 9, "%lf,%lf,%lf", &dl, &phi, &g) != 3 || !isfinite(dl) || !isfinite(phi) || !isfinite(g) ||
            phi <= 0 || phi >= 180 || g <= 0 || g >= 0.5) {
            snprintf(why, why_len, "predicted boundary %s line %d: expected boundary,DL,PHI_DEG,GAMMA with phi in "
                     "(0, 180) and Gamma in (0, 0.5)", path, lineno);
            goto fail;
        }
        if (!have_dl) out->dl = dl, have_dl = 1;
        if (fabs(dl - out->dl) > 1e-12) continue;
        if (push(out, &cap, phi, g)) {
            snprintf(why, why_len, "predicted boundary %s: out of memory", path);
            goto fail;
        }
    }
    fclose(f);
    if (!out->n) {
        snprintf(why, why_len, "predicted boundary %s: no boundary rows", path);
        campaign_predicted_free(out);
        return -1;
    }
    sort_unique(out);
    snprintf(out->source, sizeof out->source, "%s (ribbon-sim boundary CSV)", path);
    return 0;
fail:
    fclose(f);
    campaign_predicted_free(out);
    return -1;
}

int campaign_predicted_save_csv(const campaign_predicted *p, const char *path, const char *key_line, char *why,
                                size_t why_len)
{
    /* A temp name of this writer's own (pid, a counter): ribbond and ribbonctl phase / plan write
       the same cache, maybe at once, and each renames only its own whole file into place. */
    static atomic_uint seq;
    char tmp[1100];
    int fd = -1;
    for (int i = 0; i < 16 && fd < 0; i++) {
        snprintf(tmp, sizeof tmp, "%s.%ld.%u.tmp", path, (long)getpid(), atomic_fetch_add(&seq, 1u));
        fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd < 0 && errno != EEXIST) break;
    }
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (!f) {
        snprintf(why, why_len, "cannot write %s: %s", tmp, strerror(errno));
        if (fd >= 0) close(fd), remove(tmp);
        return -1;
    }
    if (key_line) fprintf(f, "%s\n", key_line);
    if (p->stop[0]) fprintf(f, "# stop: %s\n", p->stop);
    fprintf(f, "kind,dl,phi_deg,gamma,dw,dz,eig_even,eig_odd,parity_even,parity_odd\n");
    for (size_t i = 0; i < p->n; i++)
        fprintf(f, "boundary,%.17g,%.17g,%.17g,,,,,,\n", p->dl, p->phi_deg[i], p->gamma[i]);
    if (fclose(f) != 0 || rename(tmp, path) != 0) {
        remove(tmp);
        snprintf(why, why_len, "cannot write %s", path);
        return -1;
    }
    return 0;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int campaign_predicted_trace(const rod_scene *sc, double phi_lo, double phi_hi, campaign_predicted *out, char *why,
                             size_t why_len)
{
    memset(out, 0, sizeof *out);
    double t0 = now_s();
    rod_boundary_opts bo = rod_boundary_opts_default();
    rod_boundary *b = NULL;
    rod_codim2_point start;
    if (rod_boundary_start(sc, &bo, &b, &start, why, why_len) != ROD_OK) {
        rod_boundary_free(b);
        return -1;
    }
    size_t cap = 0;
    out->dl = start.dl;
    int oom = push(out, &cap, start.phi_deg, start.gamma);
    double lo = fmax(fmin(phi_lo, phi_hi), 1.0), hi = fmin(fmax(phi_lo, phi_hi), 179.0);
    rod_boundary_mark(b);
    for (int dir = 0; dir < 2 && !oom; dir++) {
        double target = dir ? hi : lo;
        if (dir) rod_boundary_return(b);
        if ((dir && target <= start.phi_deg) || (!dir && target >= start.phi_deg)) continue;
        rod_boundary_curve part = {0};
        rod_status s = rod_boundary_move(b, ROD_PAR_PHI, target, &part);
        for (size_t k = 0; k < part.n && !oom; k++) oom = push(out, &cap, part.pts[k].phi_deg, part.pts[k].gamma);
        if (s != ROD_OK) {
            size_t len = strlen(out->stop);
            snprintf(out->stop + len, sizeof out->stop - len, "%stoward %g deg: %.200s", len ? "; " : "", target,
                     part.end_reason);
        }
        rod_boundary_curve_free(&part);
    }
    rod_boundary_free(b);
    if (oom) {
        campaign_predicted_free(out);
        snprintf(why, why_len, "predicted boundary: out of memory");
        return -1;
    }
    sort_unique(out);
    snprintf(out->source, sizeof out->source, "traced from the scene (N = %d, Delta L = %g) in %.2f s", sc->nodes,
             out->dl, now_s() - t0);
    return 0;
}

int campaign_predicted_cache_read(const char *scene_text, double phi_lo, double phi_hi, const char *cache_path,
                                  campaign_predicted *out)
{
    uint64_t key = campaign_predicted_key(scene_text);
    FILE *f = cache_path ? fopen(cache_path, "r") : NULL;
    if (f) {
        unsigned long long k = 0;
        double a = 0, bb = 0;
        int ok = fscanf(f, "# campaign-boundary key=%llx phi=%lf:%lf", &k, &a, &bb) == 3;
        fclose(f);
        char w[300];
        if (ok && k == key && a <= phi_lo && bb >= phi_hi && campaign_predicted_load_csv(cache_path, out, w, sizeof w) == 0) {
            snprintf(out->source, sizeof out->source, "cache %.580s", cache_path);
            return 0;
        }
    }
    return -1;
}

int campaign_predicted_cached(const rod_scene *sc, const char *scene_text, double phi_lo, double phi_hi,
                              const char *cache_path, campaign_predicted *out, char *why, size_t why_len)
{
    uint64_t key = campaign_predicted_key(scene_text);
    if (campaign_predicted_cache_read(scene_text, phi_lo, phi_hi, cache_path, out) == 0) return 0;
    if (campaign_predicted_trace(sc, phi_lo, phi_hi, out, why, why_len)) return -1;
    if (cache_path) {
        char line[128], w[300];
        snprintf(line, sizeof line, "# campaign-boundary key=%016llx phi=%.17g:%.17g", (unsigned long long)key, phi_lo,
                 phi_hi);
        if (campaign_predicted_save_csv(out, cache_path, line, w, sizeof w)) {
            size_t len = strlen(out->source);
            snprintf(out->source + len, sizeof out->source - len, " (not cached: %.200s)", w);
        } else {
            size_t len = strlen(out->source);
            snprintf(out->source + len, sizeof out->source - len, ", cached in %.400s", cache_path);
        }
    }
    return 0;
}

int campaign_predicted_at(const campaign_predicted *p, double phi_deg, double *gamma, char *why, size_t why_len)
{
    if (!p->n || !(phi_deg >= p->phi_deg[0] - 1e-9 && phi_deg <= p->phi_deg[p->n - 1] + 1e-9)) {
        if (!p->n)
            snprintf(why, why_len, "phi %g deg is outside the model's range: no predicted boundary", phi_deg);
        else
            snprintf(why, why_len, "phi %g deg is outside the model's range %g .. %g deg (the predicted boundary, %.300s%s%.250s)",
                     phi_deg, p->phi_deg[0], p->phi_deg[p->n - 1], p->source, p->stop[0] ? "; it stopped " : "", p->stop);
        return -1;
    }
    size_t i = 0;
    while (i + 2 < p->n && p->phi_deg[i + 1] < phi_deg) i++;
    if (p->n == 1) {
        *gamma = p->gamma[0];
        return 0;
    }
    double t = (phi_deg - p->phi_deg[i]) / (p->phi_deg[i + 1] - p->phi_deg[i]);
    if (t < 0) t = 0;
    if (t > 1) t = 1;
    *gamma = p->gamma[i] + t * (p->gamma[i + 1] - p->gamma[i]);
    return 0;
}
