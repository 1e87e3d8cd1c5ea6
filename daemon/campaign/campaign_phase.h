/* campaign_phase.h: the lab's own phase diagram (campaign_phase.c; issue 35 part C, `ribbonctl
 * phase`, GET /campaign/phase): every specimen's measured regimes at its design (phi, Gamma),
 * repeated trials as counts, the boundary the experiments support per phi (campaign_edge.h), and
 * the predicted boundary beside them (campaign_predicted.h); as a figure, a CSV and JSON. */
#ifndef RIBBON_CAMPAIGN_PHASE_H
#define RIBBON_CAMPAIGN_PHASE_H

#include <jansson.h>
#include <stddef.h>

#include "campaign_edge.h"
#include "campaign_predicted.h"
#include "plot.h"
#include "store.h"

typedef struct campaign_phase {
    campaign_obs *obs;     /* one per design point (phi, Gamma), phi then Gamma ascending */
    size_t n_obs;
    campaign_edge *edges;  /* one per phi, ascending */
    size_t n_edges;
    int n_specimens;       /* specimens in the store */
    int n_trials;          /* measured trials of specimens (counted in obs) */
} campaign_phase;

/* Reads the store. Named errors (-2, why): "no specimens in the store ..." and "no measured
 * trials of any specimen ..."; -1: a store error. A trial counts once it has a measured result
 * (snapped or not); trials without a specimen are not the campaign's. */
int campaign_phase_collect(store *st, campaign_phase *out, char *why, size_t why_len);
void campaign_phase_free(campaign_phase *ph);

/* The CSV for a paper, one table, a "kind" column first:
 *   point,PHI,GAMMA,N_ASYM,N_SYM,N_OTHER,N_SPECIMENS,,,,,PRED   (a design point; PRED Gamma* there)
 *   edge,PHI,ESTIMATE,N_ASYM,N_SYM,,N_POINTS,METHOD,LO,HI,WIDTH,PRED  (the experimental boundary)
 *   predicted,PHI,GAMMA,,,,,,,,,                                 (the predicted curve's points)
 * header: kind,phi_deg,gamma,n_asym,n_sym,n_other,n_specimens_or_points,method,lo,hi,width,predicted_gamma
 * Unknown numbers are empty fields, never NaN. pred may be NULL. Written to a temporary file and
 * renamed. */
int campaign_phase_write_csv(const campaign_phase *ph, const campaign_predicted *pred, const char *path, char *why,
                             size_t why_len);
/* {"points": [...], "edges": [...], "predicted": {"source", "stop", "phi_deg": [...], "gamma": [...]}
 *  | null, "specimens": n, "trials": n}; null for unknown numbers. */
json_t *campaign_phase_json(const campaign_phase *ph, const campaign_predicted *pred);
/* The figure (PLplot PNG, plot_phase_report): the predicted map when base has one (its grid
 * fields; NULL: none), the predicted curve, the points with counts, the experimental boundary. */
int campaign_phase_png(const campaign_phase *ph, const campaign_predicted *pred, const plot_phase_data *base,
                       const char *path, char *why, size_t why_len);

#endif
