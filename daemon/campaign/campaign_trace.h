/* campaign_trace.h: the predicted boundary for ribbond's GET /campaign/phase, traced off the API
 * thread (campaign_trace.c).
 *
 * ribbond serves every API request on one thread (api_server.h), and a cold boundary cache means a
 * trace of about a second of CPU (more on a loaded machine): on that thread it held every other
 * request (the live page, GET /status, an abort) for as long. Here the cache file is read on the
 * caller's thread (cheap) and a miss starts the trace on a thread of its own; the route answers
 * 503 with Retry-After until it has landed. The last finished trace (or its failure) is kept per
 * key, so the route neither traces nor re-reads the file again for the same rig and scene. */
#ifndef RIBBON_CAMPAIGN_TRACE_H
#define RIBBON_CAMPAIGN_TRACE_H

#include "campaign_predicted.h"

typedef struct campaign_trace campaign_trace;

/* NULL when out of memory. */
campaign_trace *campaign_trace_new(void);
/* Waits for a trace still running (at most its own time: it cannot be cut short), then frees. */
void campaign_trace_free(campaign_trace *t);

/* The predicted boundary of scene sc over [phi_lo, phi_hi], keyed on key_text
 * (campaign_predicted_cached's key and cache file). Returns
 *    0  *out filled (the last trace of this key, or the cache file): free it with
 *       campaign_predicted_free;
 *    1  a trace is running (started by this call if none was): *running_s (may be NULL) its age;
 *   -1  the trace of this key failed, or could not be started: why. */
int campaign_trace_get(campaign_trace *t, const rod_scene *sc, const char *key_text, double phi_lo, double phi_hi,
                       const char *cache_path, campaign_predicted *out, double *running_s, char *why, size_t why_len);

#endif
