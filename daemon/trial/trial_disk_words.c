/* trial_disk_words.c: the free-room refusal's words (see trial_disk_words.h). */
#include "trial_disk_words.h"

#include <stdio.h>
#include <string.h>

void trial_disk_words(char *why, size_t why_len, double free_bytes, double need_mb, const char *dir)
{
    const double free_mb = free_bytes / 1e6;
    char f[64], n[64];
    for (int d = 0; d <= 6; d++) {
        snprintf(f, sizeof f, "%.*f", d, free_mb);
        snprintf(n, sizeof n, "%.*f", d, need_mb);
        if (strcmp(f, n) != 0) {
            snprintf(why, why_len, "only %s MB free in %.300s; a trial needs %s MB (trial.min_free_disk_mb)", f, dir,
                     n);
            return;
        }
    }
    snprintf(why, why_len, "only %.0f bytes free in %.300s; a trial needs %.0f bytes (trial.min_free_disk_mb)",
             free_bytes, dir, need_mb * 1e6);
}
