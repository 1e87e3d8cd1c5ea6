/* replay_rails_csv.h: the rails CSV an outside replay reads (replay.rails in a replay-mode rig
 * file): one reading "t_s,compress_mm,shear_mm" per line, on the rails' clock.
 *
 * Kept apart from trial_replay.c so the parser, which reads a file from outside, can be fuzzed on
 * its own (fuzz/fuzz_replay_rails.c) without a store, a video or the vision library. Format: an
 * optional header line (before any reading), '#' comments and blank lines anywhere, spaces and
 * tabs around the numbers, numbers plain decimal (config/cfg_number.h), t strictly increasing,
 * at least two readings, at most REPLAY_RAILS_MAX; a line longer than REPLAY_RAILS_LINE_MAX is
 * refused (never split into two readings). A position beyond REPLAY_RAILS_MAX_MM either way is
 * refused with its line (issue 33, item 12: 1e300 mm once became a "done" trial with Delta L =
 * 5e297). */
#ifndef RIBBON_DAEMON_TRIAL_REPLAY_RAILS_CSV_H
#define RIBBON_DAEMON_TRIAL_REPLAY_RAILS_CSV_H

#include <stddef.h>
#include <stdio.h>

#define REPLAY_RAILS_MAX 10000000  /* readings in a rails CSV */
#define REPLAY_RAILS_LINE_MAX 510  /* bytes of one line, without its newline */
/* mm, the largest |position| of either rail: the bound a rig file's soft limits may take
 * (config/rail_config.c, soft_min_mm and soft_max_mm in [-1e6, 1e6]), so no rig that could have
 * recorded the file reaches beyond it. */
#define REPLAY_RAILS_MAX_MM 1e6

typedef struct rail_reading {
    double t, compress_mm, shear_mm;
} rail_reading;

/* Read the whole of f (name for messages). On success 0, *rails malloc'ed (the caller frees) with
 * *n >= 2 readings. On failure -1, the reason (with the line) in why, *rails freed and NULL. */
int replay_rails_csv_read(FILE *f, const char *name, rail_reading **rails, size_t *n, char *why,
                          size_t why_len);

#endif
