// image_header.cpp: an image file's pixel size read from its header, before any decoding, so a
// huge image is refused before a decoder allocates for it (issue 17, defect 8: a 16000 x 16000 PNG
// was decoded, 2 GB at the peak, before it failed; a 100000 x 100000 one read as zero frames and
// no error). Known headers: PNG, JPEG, BMP, PNM (P1..P6). Other files are left to the decoder.
#include "image_header.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace vis {
namespace {

unsigned long be32(const unsigned char *p)
{
    return ((unsigned long)p[0] << 24) | ((unsigned long)p[1] << 16) | ((unsigned long)p[2] << 8) | p[3];
}
unsigned be16(const unsigned char *p) { return ((unsigned)p[0] << 8) | p[1]; }
long le32s(const unsigned char *p)
{
    unsigned long u = (unsigned long)p[0] | ((unsigned long)p[1] << 8) | ((unsigned long)p[2] << 16) |
                      ((unsigned long)p[3] << 24);
    return u >= 0x80000000ul ? -(long)(0x100000000ul - u) : (long)u;
}

// JPEG: walk the markers to the first start-of-frame (SOF0..SOF15 but DHT C4, JPG C8, DAC CC).
int jpeg_size(FILE *f, long *w, long *h)
{
    unsigned char b[8];
    for (int guard = 0; guard < 1000; guard++) {
        int c = std::fgetc(f);
        while (c != EOF && c != 0xFF) c = std::fgetc(f);
        while (c == 0xFF) c = std::fgetc(f);
        if (c == EOF) return 0;
        if (c == 0xD8 || c == 0x01 || (c >= 0xD0 && c <= 0xD7)) continue; // no length
        if (c == 0xD9 || c == 0xDA) return 0;                                 // no frame header
        if (std::fread(b, 1, 2, f) != 2) return 0;
        unsigned len = be16(b);
        if (len < 2) return 0;
        if (c >= 0xC0 && c <= 0xCF && c != 0xC4 && c != 0xC8 && c != 0xCC) {
            if (len < 7 || std::fread(b, 1, 5, f) != 5) return 0;
            *h = be16(b + 1);
            *w = be16(b + 3);
            return 1;
        }
        if (std::fseek(f, (long)len - 2, SEEK_CUR) != 0) return 0;
    }
    return 0;
}

// PNM: "P5 <w> <h> ...", '#' comments between the fields.
int pnm_size(FILE *f, long *w, long *h)
{
    long v[2];
    for (int k = 0; k < 2; k++) {
        int c = std::fgetc(f);
        for (;;) {
            if (c == '#')
                while (c != EOF && c != '\n') c = std::fgetc(f);
            else if (c == ' ' || c == '\t' || c == '\r' || c == '\n')
                c = std::fgetc(f);
            else
                break;
        }
        if (c < '0' || c > '9') return 0;
        long x = 0;
        while (c >= '0' && c <= '9') {
            if (x > 1000000000L) return 0;
            x = 10 * x + (c - '0');
            c = std::fgetc(f);
        }
        v[k] = x;
    }
    *w = v[0];
    *h = v[1];
    return 1;
}

}  // namespace

int image_header_size(const char *path, long *w, long *h)
{
    FILE *f = std::fopen(path, "rb");
    if (!f) return -1;
    unsigned char b[32];
    size_t n = std::fread(b, 1, sizeof b, f);
    int r = 0;
    static const unsigned char png_sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (n >= 24 && !std::memcmp(b, png_sig, 8) && !std::memcmp(b + 12, "IHDR", 4)) {
        *w = (long)be32(b + 16);
        *h = (long)be32(b + 20);
        r = 1;
    } else if (n >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) {
        std::fseek(f, 2, SEEK_SET);
        r = jpeg_size(f, w, h);
    } else if (n >= 26 && b[0] == 'B' && b[1] == 'M') {
        *w = le32s(b + 18);
        long hh = le32s(b + 22);
        *h = hh < 0 ? -hh : hh; // negative: top-down rows
        r = 1;
    } else if (n >= 3 && b[0] == 'P' && b[1] >= '1' && b[1] <= '6') {
        std::fseek(f, 2, SEEK_SET);
        r = pnm_size(f, w, h);
    }
    std::fclose(f);
    return r;
}

vis_status image_size_check(const char *path, vis_error *err)
{
    long w = 0, h = 0;
    int r = image_header_size(path, &w, &h);
    if (r <= 0) return VIS_OK; // not a header we know (or unreadable): the decoder says
    if (w > VIS_MAX_IMAGE_SIDE || h > VIS_MAX_IMAGE_SIDE || (double)w * (double)h > VIS_MAX_IMAGE_PIXELS)
        return fail(err, VIS_ERR_TOO_LARGE,
                    "image too large: %s is %ld x %ld px, above the limit of %d px a side and %.0f Mpx "
                    "(refused before decoding)",
                    path, w, h, VIS_MAX_IMAGE_SIDE, VIS_MAX_IMAGE_PIXELS / 1e6);
    return VIS_OK;
}

}  // namespace vis
