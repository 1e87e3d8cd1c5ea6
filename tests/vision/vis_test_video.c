/* vis_test_video.c: small video helpers shared by the vision tests (see vis_test_video.h). */
#include "vis_test_video.h"

#include <stdio.h>
#include <string.h>

int vt_same_measure(const vis_measure *a, const vis_measure *b)
{
    return a->reason == b->reason && !memcmp(&a->dz, &b->dz, sizeof a->dz) && !memcmp(&a->a, &b->a, sizeof a->a) &&
           !memcmp(&a->quality, &b->quality, sizeof a->quality) &&
           !memcmp(&a->length_mm, &b->length_mm, sizeof a->length_mm) &&
           !memcmp(a->mid_px, b->mid_px, sizeof a->mid_px) &&
           !memcmp(&a->residual_px, &b->residual_px, sizeof a->residual_px);
}

int vt_write_frames(const char *path, vis_frame *const *frames, int n, double fps)
{
    vis_error err;
    const size_t len = strlen(path);
    const int w = vis_frame_width(frames[0]), h = vis_frame_height(frames[0]);
    vis_video_writer *vw = len > 4 && strcmp(path + len - 4, ".avi") == 0
                               ? vis_video_writer_open_y800(path, w, h, fps, &err)
                               : vis_video_writer_open(path, w, h, 1, fps, &err);
    if (!vw) {
        printf("%s: %s\n", path, err.message);
        return -1;
    }
    for (int i = 0; i < n; i++)
        if (vis_video_writer_write(vw, frames[i], &err) != VIS_OK) {
            printf("%s: frame %d: %s\n", path, i, err.message);
            vis_video_writer_close(vw);
            return -1;
        }
    vis_video_writer_close(vw);
    return 0;
}

int vt_cut_copy(const char *from, const char *to, long num, long den)
{
    FILE *in = fopen(from, "rb"), *out = fopen(to, "wb");
    int rc = in && out ? 0 : -1;
    if (!rc) {
        fseek(in, 0, SEEK_END);
        const long size = ftell(in);
        fseek(in, 0, SEEK_SET);
        for (long k = 0; k < size * num / den && !rc; k++)
            rc = fputc(fgetc(in), out) == EOF ? -1 : 0;
    }
    if (in)
        fclose(in);
    if (out && fclose(out) != 0)
        rc = -1;
    return rc;
}
