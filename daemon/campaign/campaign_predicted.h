/* campaign_predicted.h: the predicted regime boundary Gamma*(phi) a campaign is compared with and
 * planned from (campaign_predicted.c): the codimension-2 curve of `ribbon-sim boundary`
 * (sim/rod_boundary.h), read from its CSV, or traced here from the rig's scene and cached.
 *
 * Cost: the trace is cheap next to a trial (mock scene, N = 61: 0.4 s for phi 60..120 on an idle
 * core; docs/boundary.md), but ribbonctl phase / plan and the API ask for it on every call, so
 * the traced curve is kept in a cache file in ribbon-sim's CSV format with one first line
 * "# campaign-boundary key=HEX phi=A:B" (key: FNV-1a of the scene's text; A:B the phi range asked
 * for). A cache whose key differs or whose range does not cover the request is traced again. */
#ifndef RIBBON_CAMPAIGN_PREDICTED_H
#define RIBBON_CAMPAIGN_PREDICTED_H

#include <stddef.h>
#include <stdint.h>

#include "scene.h"

/* The phi range ribbonctl and ribbond trace (and cache) the predicted boundary over, whatever is
 * asked: one cache serves the phase diagram, the planner and the API. */
#define CAMPAIGN_PHI_TRACE_LO 20.0
#define CAMPAIGN_PHI_TRACE_HI 160.0

typedef struct campaign_predicted {
    double *phi_deg, *gamma; /* n points, phi ascending */
    size_t n;
    double dl;               /* Delta L of the curve */
    char source[600];        /* where it came from: "FILE (ribbon-sim boundary CSV)", "cache FILE",
                                "traced (0.41 s)" */
    char stop[300];          /* why a trace ended short of the range asked ("" when covered) */
} campaign_predicted;

/* Reads ribbon-sim boundary's CSV (rows "boundary", the first Delta L's; '#' lines skipped, but
 * "# stop: WHY", the cache's note of where its trace stopped, is kept in stop).
 * -1 with why naming the file and line; a file without boundary rows is an error. */
int campaign_predicted_load_csv(const char *path, campaign_predicted *out, char *why, size_t why_len);
/* Writes it back in that format (the cache), key line first when key_line is not NULL. */
int campaign_predicted_save_csv(const campaign_predicted *p, const char *path, const char *key_line, char *why,
                                size_t why_len);
/* Traces the scene's boundary from its own phi down to phi_lo and up to phi_hi (clamped to
 * [1, 179] deg). A trace that stops early keeps its points and says why in stop; -1 only when
 * no codimension-2 point was found at all (why). */
int campaign_predicted_trace(const rod_scene *sc, double phi_lo, double phi_hi, campaign_predicted *out, char *why,
                             size_t why_len);
/* The cache alone: cache_path's curve when its key (FNV-1a of scene_text) matches and it covers
 * [phi_lo, phi_hi]: 0, else -1 (no file, another key or range, unreadable); never traces. */
int campaign_predicted_cache_read(const char *scene_text, double phi_lo, double phi_hi, const char *cache_path,
                                  campaign_predicted *out);
/* The cached trace: cache_path's curve when its key (FNV-1a of scene_text) matches and it covers
 * [phi_lo, phi_hi], else a new trace written there (a cache that cannot be written is not an
 * error: source says so). */
int campaign_predicted_cached(const rod_scene *sc, const char *scene_text, double phi_lo, double phi_hi,
                              const char *cache_path, campaign_predicted *out, char *why, size_t why_len);
/* Gamma* at phi by linear interpolation: 0, or -1 with why ("phi 30 deg is outside the model's
 * range 45.2 .. 135 deg: ...") when phi lies outside the curve. */
int campaign_predicted_at(const campaign_predicted *p, double phi_deg, double *gamma, char *why, size_t why_len);
void campaign_predicted_free(campaign_predicted *p);
/* The text the cache is keyed on: the rig file's text, a separator, the scene file's (unreadable
 * files count as empty), so ribbonctl and ribbond share one cache per rig. malloc'ed; NULL when out
 * of memory. */
char *campaign_predicted_key_text(const char *rig_path, const char *scene_path);
/* FNV-1a 64 of a text (the cache key). */
uint64_t campaign_predicted_key(const char *text);

#endif
