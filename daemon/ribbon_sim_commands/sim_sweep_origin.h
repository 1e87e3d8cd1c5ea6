/* sim_sweep_origin.h: what made a sweep file, written as its line 2 (sim_sweep_row.h), so files
 * from different sweeps are never mixed (issue 33, item 11: sweep-merge joined shards made at
 * different N or on different grids, and a resume would append rows of another scene):
 *
 *     ribbon-sim VERSION; scene HASH; nodes N; phi A:B:n; gamma C:D:m; dl E:F:k; gamma-tol T; seed S
 *
 * HASH is FNV-1a (64 bits) of the scene as the sweep uses it: every field printed exactly (%a),
 * but the mesh size (its own field) and what the grid replaces per point (crease magnitude,
 * position, Delta L and the imperfection; the crease's sign is kept). Nothing that only splits the work is in it (--jobs,
 * --shard, mpirun, --heartbeat), so one run, its shards and its MPI ranks write the same line and
 * their merged files stay identical line for line. */
#ifndef RIBBON_DAEMON_SIM_SWEEP_ORIGIN_H
#define RIBBON_DAEMON_SIM_SWEEP_ORIGIN_H

#include <stddef.h>

#include "sim_sweep_task.h"

/* The origin line of a sweep of sp on the grid phi (pa:pb:np) x sp->gamma (ga:gb:ng) x dl
 * (da:db:nd), into out (SWEEP_ORIGIN_MAX bytes). */
void sweep_origin_format(const sweep_spec *sp, double pa, double pb, int np, double ga, double gb, int ng, double da,
                         double db, int nd, char *out, size_t out_len);

/* 0 when a and b are the same origin; else -1 with the first field that differs, both ways
 * ("nodes 41 against nodes 61"), in what. */
int sweep_origin_compare(const char *a, const char *b, char *what, size_t what_len);

/* Whether a sweep with origin `run` may resume the file made with origin `file`: every field the
 * same but phi and dl, whose grid points must each be one of the file's (so `--dl X:X:1 --plot`
 * on one Delta L of the file computes nothing new). 0, or -1 with the reason in what. */
int sweep_origin_resumable(const char *file, const char *run, char *what, size_t what_len);

#endif
