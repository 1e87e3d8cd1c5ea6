/* campaign_phase.c: the lab's phase diagram from the store: specimens' measured regimes pooled
 * per design point, the experimental boundary per phi, and its CSV, JSON and figure
 * (campaign_phase.h). A design point is a specimen's (phi_deg, fold_position) to 1e-9: two
 * specimens folded to one design are one point with both their trials. */
#include "campaign_phase.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SAME 1e-9

void campaign_phase_free(campaign_phase *ph)
{
    if (!ph) return;
    free(ph->obs);
    free(ph->edges);
    memset(ph, 0, sizeof *ph);
}

static int obs_cmp(const void *a, const void *b)
{
    const campaign_obs *x = a, *y = b;
    if (x->phi_deg != y->phi_deg) return x->phi_deg < y->phi_deg ? -1 : 1;
    return x->gamma < y->gamma ? -1 : x->gamma > y->gamma;
}

int campaign_phase_collect(store *st, campaign_phase *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    store_specimen *sp = NULL;
    store_trial *tr = NULL;
    size_t nsp = 0, ntr = 0;
    if (store_specimen_list(st, &sp, &nsp, why, why_len) != STORE_OK) return -1;
    if (!nsp) {
        snprintf(why, why_len, "no specimens in the store: add them (ribbonctl specimen add NAME --phi DEG --gamma G) "
                               "and trial them (ribbonctl start --specimen NAME)");
        return -2;
    }
    if (store_trial_list(st, &tr, &ntr, why, why_len) != STORE_OK) {
        free(sp);
        return -1;
    }
    out->n_specimens = (int)nsp;
    out->obs = calloc(nsp, sizeof *out->obs);
    int *seen = calloc(nsp, sizeof *seen);
    if (!out->obs || !seen) {
        free(sp), free(tr), free(seen);
        campaign_phase_free(out);
        snprintf(why, why_len, "phase: out of memory");
        return -1;
    }
    for (size_t t = 0; t < ntr; t++) {
        if (!tr[t].specimen_id || tr[t].snapped < 0) continue;
        size_t s = 0;
        while (s < nsp && sp[s].id != tr[t].specimen_id) s++;
        if (s == nsp || !isfinite(sp[s].phi_deg) || !isfinite(sp[s].fold_position)) continue;
        size_t k = 0;
        while (k < out->n_obs &&
               !(fabs(out->obs[k].phi_deg - sp[s].phi_deg) < SAME && fabs(out->obs[k].gamma - sp[s].fold_position) < SAME))
            k++;
        if (k == out->n_obs) {
            out->obs[k] = (campaign_obs){.phi_deg = sp[s].phi_deg, .gamma = sp[s].fold_position};
            out->n_obs++;
        }
        campaign_obs *o = &out->obs[k];
        if (tr[t].regime_measured == STORE_REGIME_ASYMMETRIC) o->n_asym++;
        else if (tr[t].regime_measured == STORE_REGIME_SYMMETRIC) o->n_sym++;
        else {
            o->n_other++;
            if (tr[t].snapped == 1 && tr[t].regime_measured == STORE_REGIME_UNKNOWN) o->n_unknown++;
        }
        if (!seen[s]) {
            seen[s] = 1;
            o->n_specimens++;
        }
        out->n_trials++;
    }
    free(sp), free(tr), free(seen);
    if (!out->n_trials) {
        campaign_phase_free(out);
        snprintf(why, why_len, "no measured trials of any specimen yet (%zu specimens in the store): run some "
                               "(ribbonctl start --specimen NAME, or the queue)", nsp);
        return -2;
    }
    qsort(out->obs, out->n_obs, sizeof *out->obs, obs_cmp);
    double phis[256];
    size_t np = campaign_edge_phis(out->obs, out->n_obs, phis, 256);
    out->edges = calloc(np, sizeof *out->edges);
    if (!out->edges) {
        campaign_phase_free(out);
        snprintf(why, why_len, "phase: out of memory");
        return -1;
    }
    for (size_t j = 0; j < np; j++) campaign_edge_fit(out->obs, out->n_obs, phis[j], &out->edges[j]);
    out->n_edges = np;
    return 0;
}

/* "%.6g" or "" for NaN. */
static const char *num(char *buf, size_t len, double v)
{
    if (isfinite(v)) snprintf(buf, len, "%.8g", v);
    else buf[0] = '\0';
    return buf;
}

static double pred_at(const campaign_predicted *pred, double phi)
{
    double g;
    char w[8];
    if (pred && campaign_predicted_at(pred, phi, &g, w, sizeof w) == 0) return g;
    return NAN;
}

int campaign_phase_write_csv(const campaign_phase *ph, const campaign_predicted *pred, const char *path, char *why,
                             size_t why_len)
{
    char tmp[1100];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = fopen(tmp, "w");
    if (!f) {
        snprintf(why, why_len, "cannot write %s", tmp);
        return -1;
    }
    char a[32], b[32], c[32], d[32], e[32];
    fprintf(f, "kind,phi_deg,gamma,n_asym,n_sym,n_other,n_specimens_or_points,method,lo,hi,width,predicted_gamma\n");
    for (size_t k = 0; k < ph->n_obs; k++) {
        const campaign_obs *o = &ph->obs[k];
        fprintf(f, "point,%s,%s,%d,%d,%d,%d,,,,,%s\n", num(a, 32, o->phi_deg), num(b, 32, o->gamma), o->n_asym,
                o->n_sym, o->n_other, o->n_specimens, num(c, 32, pred_at(pred, o->phi_deg)));
    }
    for (size_t k = 0; k < ph->n_edges; k++) {
        const campaign_edge *x = &ph->edges[k];
        fprintf(f, "edge,%s,%s,%d,%d,,%d,%s,%s,%s,%s,", num(a, 32, x->phi_deg), num(b, 32, x->gamma), x->n_asym,
                x->n_sym, x->n_points, campaign_edge_method_name(x->method), num(c, 32, x->lo), num(d, 32, x->hi),
                num(e, 32, x->width));
        fprintf(f, "%s\n", num(a, 32, pred_at(pred, x->phi_deg)));
    }
    for (size_t k = 0; pred && k < pred->n; k++)
        fprintf(f, "predicted,%s,%s,,,,,,,,,\n", num(a, 32, pred->phi_deg[k]), num(b, 32, pred->gamma[k]));
    if (fclose(f) != 0 || rename(tmp, path) != 0) {
        remove(tmp);
        snprintf(why, why_len, "cannot write %s", path);
        return -1;
    }
    return 0;
}

static json_t *jnum(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

json_t *campaign_phase_json(const campaign_phase *ph, const campaign_predicted *pred)
{
    json_t *pts = json_array(), *edges = json_array();
    for (size_t k = 0; k < ph->n_obs; k++) {
        const campaign_obs *o = &ph->obs[k];
        json_array_append_new(pts, json_pack("{s:o,s:o,s:i,s:i,s:i,s:i,s:o}", "phi_deg", jnum(o->phi_deg), "gamma",
                                             jnum(o->gamma), "n_asym", o->n_asym, "n_sym", o->n_sym, "n_other",
                                             o->n_other, "n_specimens", o->n_specimens, "predicted_gamma",
                                             jnum(pred_at(pred, o->phi_deg))));
    }
    for (size_t k = 0; k < ph->n_edges; k++) {
        const campaign_edge *x = &ph->edges[k];
        json_array_append_new(edges, json_pack("{s:o,s:s,s:o,s:o,s:o,s:o,s:i,s:i,s:i,s:o}", "phi_deg",
                                               jnum(x->phi_deg), "method", campaign_edge_method_name(x->method),
                                               "gamma", jnum(x->gamma), "lo", jnum(x->lo), "hi", jnum(x->hi), "width",
                                               jnum(x->width), "n_asym", x->n_asym, "n_sym", x->n_sym, "n_points",
                                               x->n_points, "predicted_gamma", jnum(pred_at(pred, x->phi_deg))));
    }
    json_t *pj = json_null();
    if (pred) {
        json_t *pp = json_array(), *pg = json_array();
        for (size_t k = 0; k < pred->n; k++) {
            json_array_append_new(pp, json_real(pred->phi_deg[k]));
            json_array_append_new(pg, json_real(pred->gamma[k]));
        }
        pj = json_pack("{s:s,s:s,s:f,s:o,s:o}", "source", pred->source, "stop", pred->stop, "dl", pred->dl, "phi_deg",
                       pp, "gamma", pg);
    }
    return json_pack("{s:o,s:o,s:o,s:i,s:i}", "points", pts, "edges", edges, "predicted", pj, "specimens",
                     ph->n_specimens, "trials", ph->n_trials);
}

int campaign_phase_png(const campaign_phase *ph, const campaign_predicted *pred, const plot_phase_data *base,
                       const char *path, char *why, size_t why_len)
{
    plot_phase_data d;
    if (base) d = *base;
    else plot_phase_data_default(&d);
    /* one marker per regime present at a point, with its count */
    plot_phase_trial *t = calloc(3 * ph->n_obs + 1, sizeof *t);
    plot_phase_edge *e = calloc(ph->n_edges + 1, sizeof *e);
    int *cnt = calloc(3 * ph->n_obs + 1, sizeof *cnt);
    if (!t || !e || !cnt) {
        free(t), free(e), free(cnt);
        snprintf(why, why_len, "phase figure: out of memory");
        return -1;
    }
    size_t m = 0;
    for (size_t k = 0; k < ph->n_obs; k++) {
        const campaign_obs *o = &ph->obs[k];
        /* symmetric and asymmetric at one point side by side would hide each other: nudge them
         * apart by a fraction of a degree in phi */
        int both = o->n_asym && o->n_sym;
        if (o->n_asym) cnt[m] = o->n_asym, t[m++] = (plot_phase_trial){o->gamma, o->phi_deg + (both ? 0.6 : 0), PLOT_REGIME_ASYMMETRIC};
        if (o->n_sym) cnt[m] = o->n_sym, t[m++] = (plot_phase_trial){o->gamma, o->phi_deg - (both ? 0.6 : 0), PLOT_REGIME_SYMMETRIC};
        if (o->n_other) cnt[m] = o->n_other, t[m++] = (plot_phase_trial){o->gamma, o->phi_deg, PLOT_REGIME_NO_SNAP};
    }
    for (size_t k = 0; k < ph->n_edges; k++)
        e[k] = (plot_phase_edge){ph->edges[k].phi_deg, ph->edges[k].gamma, ph->edges[k].lo, ph->edges[k].hi};
    if (!d.title) d.title = "the lab's phase diagram";
    d.trials = t;
    d.n_trials = m;
    d.trial_counts = cnt;
    d.edges = e;
    d.n_edges = ph->n_edges;
    if (pred && pred->n) {
        d.boundary_gamma = pred->gamma;
        d.boundary_phi_deg = pred->phi_deg;
        d.n_boundary = pred->n;
    }
    plot_status s = plot_phase_report(path, &d, why, why_len);
    free(t), free(e), free(cnt);
    return s == PLOT_OK ? 0 : -1;
}
