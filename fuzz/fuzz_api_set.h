/* fuzz_api_set.h: what the fuzz targets of API requests (fuzz_api_request.c, fuzz_api_headers.c)
 * check of an override that POST /trials accepted: its key is one a trial may change, read
 * independently of daemon/api/api_overrides.c (a list of what is allowed, not the table's rows
 * and first-match rule), so a table row or a key spelling that lets a path, the API, a rail limit
 * or the twin through is a finding (issue 33, item 5). */
#ifndef RIBBON_FUZZ_API_SET_H
#define RIBBON_FUZZ_API_SET_H

/* abort()s (fuzz_fail, as who) unless ovr's key is ribbon.*, folds.*, imperfection.*,
 * protocol.*, snap.*, mesh.*, solver.*, specimen.* but min_clamp_gap_mm, or trial.hold_s,
 * post_snap_s, compress_speed_mm_s, return_speed_mm_s. */
void fuzz_check_api_override(const char *who, const char *ovr);

#endif
