/* vis_test_video.h: small video helpers shared by the vision tests (write frames, cut a file,
 * compare two results bit for bit). */
#ifndef VIS_TEST_VIDEO_H
#define VIS_TEST_VIDEO_H

#include "vision.h"

/* Every field of a and b the same bits (field by field: memcmp would compare padding too). */
int vt_same_measure(const vis_measure *a, const vis_measure *b);
/* Write n grey frames to `path`: raw Y800 when it ends in .avi, FFV1 otherwise. 0, or -1 with the
 * reason printed. */
int vt_write_frames(const char *path, vis_frame *const *frames, int n, double fps);
/* Copy the first size * num / den bytes of `from` into `to` (a file cut short). 0, or -1. */
int vt_cut_copy(const char *from, const char *to, long num, long den);

#endif
