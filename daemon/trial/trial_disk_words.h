/* trial_disk_words.h: the words a trial refuses to start with when its video directory has less
 * room than trial.min_free_disk_mb. Kept apart so the wording is tested on its own: the figures
 * are printed with as many decimals as it takes for the free room to read smaller than the need
 * (issue 33: "only 1 MB free; a trial needs 1 MB" was 0.6 MB rounded up), and in bytes when even
 * six decimals of a MB cannot tell them apart. */
#ifndef RIBBON_DAEMON_TRIAL_DISK_WORDS_H
#define RIBBON_DAEMON_TRIAL_DISK_WORDS_H

#include <stddef.h>

/* "only F MB free in DIR; a trial needs N MB (trial.min_free_disk_mb)" into why, with
 * free_bytes < need_mb * 1e6 (the caller's test) showing as F < N. */
void trial_disk_words(char *why, size_t why_len, double free_bytes, double need_mb, const char *dir);

#endif
