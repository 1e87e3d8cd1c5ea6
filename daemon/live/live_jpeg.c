/* live_jpeg.c: overlay and JPEG encoding of a live frame (see live_jpeg.h). The overlay is drawn
 * into an RGB copy: line segments between consecutive centreline points (one pixel wide,
 * stepped at most one pixel at a time), filled squares for the clamp points and the midpoint. */
#include "live_jpeg.h"

#include <stdio.h> /* before jpeglib.h, which uses FILE */

#include <jpeglib.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void put(unsigned char *rgb, int w, int h, int x, int y, const unsigned char c[3])
{
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    memcpy(rgb + ((size_t)y * (size_t)w + (size_t)x) * 3, c, 3);
}

static void square(unsigned char *rgb, int w, int h, double u, double v, int r, const unsigned char c[3])
{
    if (!isfinite(u) || !isfinite(v)) return;
    int x0 = (int)lround(u), y0 = (int)lround(v);
    for (int dy = -r; dy <= r; dy++)
        for (int dx = -r; dx <= r; dx++) put(rgb, w, h, x0 + dx, y0 + dy, c);
}

static void segment(unsigned char *rgb, int w, int h, double u0, double v0, double u1, double v1,
                    const unsigned char c[3])
{
    if (!isfinite(u0) || !isfinite(v0) || !isfinite(u1) || !isfinite(v1)) return;
    double len = fmax(fabs(u1 - u0), fabs(v1 - v0));
    if (len > 4.0 * (w + h)) return; /* a wild point: not drawn */
    int steps = (int)ceil(len);
    if (steps < 1) steps = 1;
    for (int k = 0; k <= steps; k++) {
        double t = (double)k / steps;
        int x = (int)lround(u0 + t * (u1 - u0)), y = (int)lround(v0 + t * (v1 - v0));
        put(rgb, w, h, x, y, c);
        put(rgb, w, h, x, y + 1, c);
    }
}

int live_jpeg_encode(const live_frame *f, int quality, unsigned char **jpg, size_t *len, char *why, size_t why_len)
{
    *jpg = NULL;
    *len = 0;
    if (!f || !f->pixels || f->width <= 0 || f->height <= 0 || (f->channels != 1 && f->channels != 3)) {
        snprintf(why, why_len, "no camera frame to encode");
        return -1;
    }
    int w = f->width, h = f->height;
    unsigned char *rgb = malloc((size_t)w * (size_t)h * 3);
    if (!rgb) {
        snprintf(why, why_len, "out of memory for a %dx%d frame", w, h);
        return -1;
    }
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
        const uint8_t *p = f->pixels + i * (size_t)f->channels;
        if (f->channels == 1) rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = p[0];
        else {
            rgb[3 * i] = p[2];
            rgb[3 * i + 1] = p[1];
            rgb[3 * i + 2] = p[0];
        }
    }
    static const unsigned char green[3] = {40, 220, 60}, red[3] = {230, 40, 40}, blue[3] = {60, 120, 255};
    if (f->n_uv >= 2) {
        for (size_t k = 0; k + 1 < f->n_uv; k++)
            segment(rgb, w, h, f->uv[2 * k], f->uv[2 * k + 1], f->uv[2 * k + 2], f->uv[2 * k + 3], green);
        square(rgb, w, h, f->uv[0], f->uv[1], 3, red);
        square(rgb, w, h, f->uv[2 * (f->n_uv - 1)], f->uv[2 * (f->n_uv - 1) + 1], 3, red);
        size_t m = f->n_uv / 2; /* points are evenly spaced along the arc: the middle one */
        square(rgb, w, h, f->uv[2 * m], f->uv[2 * m + 1], 3, blue);
    }
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr jerr;
    c.err = jpeg_std_error(&jerr); /* errors only on bad parameters, which are checked above */
    jpeg_create_compress(&c);
    unsigned char *out = NULL;
    unsigned long out_len = 0;
    jpeg_mem_dest(&c, &out, &out_len);
    c.image_width = (JDIMENSION)w;
    c.image_height = (JDIMENSION)h;
    c.input_components = 3;
    c.in_color_space = JCS_RGB;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, quality < 1 ? 1 : quality > 100 ? 100 : quality, TRUE);
    jpeg_start_compress(&c, TRUE);
    while (c.next_scanline < c.image_height) {
        JSAMPROW row = rgb + (size_t)c.next_scanline * (size_t)w * 3;
        jpeg_write_scanlines(&c, &row, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    free(rgb);
    if (!out || out_len == 0) {
        free(out);
        snprintf(why, why_len, "JPEG encoding produced nothing");
        return -1;
    }
    *jpg = out;
    *len = out_len;
    return 0;
}
