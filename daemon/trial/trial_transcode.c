/* trial_transcode.c: raw Y800 AVI -> FFV1 in Matroska, verified bit for bit (trial_transcode.h).
 *
 * Layout: a small reader (demux + decode to grey AVFrames, one frame at a time) serves both the
 * encode pass and the verify pass, so the verify reads the two files exactly as a replay would
 * read bytes from disk, not the encoder's own buffers. */
#include "trial_transcode.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>

trial_transcode_params trial_transcode_params_default(void)
{
    trial_transcode_params p;
    memset(&p, 0, sizeof p);
    p.threads = 2;
    p.slices = 4;
    p.range_coder = 0;
    p.corrupt_frame = -1;
    return p;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void av_why(char *why, size_t why_len, const char *what, const char *path, int e)
{
    char b[128];
    av_strerror(e, b, sizeof b);
    snprintf(why, why_len, "%s %s: %s", what, path, b);
}

/* ---- reader ---- */

typedef struct av_reader {
    AVFormatContext *fmt;
    AVCodecContext *dec;
    AVPacket *pkt;
    AVFrame *frm;
    int stream;
    int flushed;
    const char *path;
} av_reader;

static void reader_close(av_reader *r)
{
    avcodec_free_context(&r->dec);
    avformat_close_input(&r->fmt);
    av_packet_free(&r->pkt);
    av_frame_free(&r->frm);
}

static int reader_open(av_reader *r, const char *path, char *why, size_t why_len)
{
    memset(r, 0, sizeof *r);
    r->path = path;
    int e = avformat_open_input(&r->fmt, path, NULL, NULL);
    if (e < 0) {
        av_why(why, why_len, "cannot open video", path, e);
        return -1;
    }
    if ((e = avformat_find_stream_info(r->fmt, NULL)) < 0) {
        av_why(why, why_len, "no stream information in", path, e);
        reader_close(r);
        return -1;
    }
    const AVCodec *codec = NULL;
    r->stream = av_find_best_stream(r->fmt, AVMEDIA_TYPE_VIDEO, -1, -1, &codec, 0);
    if (r->stream < 0 || !codec) {
        snprintf(why, why_len, "%s holds no video stream this build can decode", path);
        reader_close(r);
        return -1;
    }
    r->dec = avcodec_alloc_context3(codec);
    r->pkt = av_packet_alloc();
    r->frm = av_frame_alloc();
    if (!r->dec || !r->pkt || !r->frm) {
        snprintf(why, why_len, "video %s: out of memory", path);
        reader_close(r);
        return -1;
    }
    avcodec_parameters_to_context(r->dec, r->fmt->streams[r->stream]->codecpar);
    r->dec->thread_count = 1;
    if ((e = avcodec_open2(r->dec, codec, NULL)) < 0) {
        av_why(why, why_len, "cannot open the decoder of", path, e);
        reader_close(r);
        return -1;
    }
    return 0;
}

/* 1: the next frame is in r->frm (8-bit grey, else an error); 0: no more; -1: error (why). */
static int reader_next(av_reader *r, long index, char *why, size_t why_len)
{
    for (int guard = 0; guard < 1000000; guard++) {
        int e = avcodec_receive_frame(r->dec, r->frm);
        if (e == 0) {
            if (r->frm->format != AV_PIX_FMT_GRAY8) {
                const char *n = av_get_pix_fmt_name((enum AVPixelFormat)r->frm->format);
                snprintf(why, why_len, "video %s: frame %ld is %s, not 8-bit grey (Y800)", r->path, index,
                         n ? n : "of an unknown format");
                return -1;
            }
            return 1;
        }
        if (e == AVERROR_EOF) return 0;
        if (e != AVERROR(EAGAIN)) {
            av_why(why, why_len, "cannot decode a frame of", r->path, e);
            return -1;
        }
        if (r->flushed) return 0;
        e = av_read_frame(r->fmt, r->pkt);
        if (e == AVERROR_EOF) {
            avcodec_send_packet(r->dec, NULL);
            r->flushed = 1;
            continue;
        }
        if (e < 0) {
            av_why(why, why_len, "cannot read", r->path, e);
            return -1;
        }
        if (r->pkt->stream_index != r->stream) {
            av_packet_unref(r->pkt);
            continue;
        }
        e = avcodec_send_packet(r->dec, r->pkt);
        av_packet_unref(r->pkt);
        if (e < 0) {
            char b[128];
            av_strerror(e, b, sizeof b);
            snprintf(why, why_len, "video %s: frame %ld cannot be decoded: %s", r->path, index, b);
            return -1;
        }
    }
    snprintf(why, why_len, "video %s: no frame after a million packets", r->path);
    return -1;
}

/* ---- compare ---- */

int trial_transcode_compare(const char *a_path, const char *b_path, const int crop[4], long *n, char *why,
                            size_t why_len)
{
    av_reader a, b;
    if (n) *n = 0;
    if (reader_open(&a, a_path, why, why_len)) return -1;
    if (reader_open(&b, b_path, why, why_len)) {
        reader_close(&a);
        return -1;
    }
    int rc = -1;
    long f = 0;
    for (;; f++) {
        int ha = reader_next(&a, f, why, why_len);
        if (ha < 0) break;
        int hb = reader_next(&b, f, why, why_len);
        if (hb < 0) break;
        if (!ha || !hb) {
            if (ha == hb) rc = 0;
            else snprintf(why, why_len, "verify: %s ends after %ld frames, %s holds more", ha ? b_path : a_path, f,
                          ha ? a_path : b_path);
            break;
        }
        int x0 = crop ? crop[0] : 0, y0 = crop ? crop[1] : 0;
        int w = crop ? crop[2] : a.frm->width, h = crop ? crop[3] : a.frm->height;
        if (x0 < 0 || y0 < 0 || x0 + w > a.frm->width || y0 + h > a.frm->height || b.frm->width != w ||
            b.frm->height != h) {
            snprintf(why, why_len, "verify: frame %ld is %dx%d in %s, %dx%d+%d+%d of %s's %dx%d expected", f,
                     b.frm->width, b.frm->height, b_path, w, h, x0, y0, a_path, a.frm->width, a.frm->height);
            break;
        }
        int bad_y = -1;
        for (int y = 0; y < h && bad_y < 0; y++) {
            const uint8_t *ra = a.frm->data[0] + (size_t)(y0 + y) * (size_t)a.frm->linesize[0] + (size_t)x0;
            const uint8_t *rb = b.frm->data[0] + (size_t)y * (size_t)b.frm->linesize[0];
            if (memcmp(ra, rb, (size_t)w) != 0) {
                int x = 0;
                while (x < w && ra[x] == rb[x]) x++;
                snprintf(why, why_len, "verify: frame %ld differs at pixel (%d, %d): %u in %s, %u in %s", f, x, y,
                         ra[x], a_path, rb[x], b_path);
                bad_y = y;
            }
        }
        if (bad_y >= 0) break;
    }
    if (n) *n = f;
    reader_close(&a);
    reader_close(&b);
    return rc;
}

/* ---- encode ---- */

typedef struct av_writer {
    AVFormatContext *oc;
    AVCodecContext *enc;
    AVStream *st;
    AVPacket *pkt;
    const char *path;
} av_writer;

static void writer_free(av_writer *w)
{
    avcodec_free_context(&w->enc);
    if (w->oc) {
        if (w->oc->pb) avio_closep(&w->oc->pb);
        avformat_free_context(w->oc);
        w->oc = NULL;
    }
    av_packet_free(&w->pkt);
}

static int writer_open(av_writer *w, const char *path, int width, int height, AVRational tb,
                       const trial_transcode_params *p, char *why, size_t why_len)
{
    memset(w, 0, sizeof *w);
    w->path = path;
    const AVCodec *c = avcodec_find_encoder(AV_CODEC_ID_FFV1);
    if (!c) {
        snprintf(why, why_len, "this libavcodec has no FFV1 encoder");
        return -1;
    }
    int e = avformat_alloc_output_context2(&w->oc, NULL, "matroska", path);
    if (e < 0 || !w->oc) {
        av_why(why, why_len, "cannot make a Matroska file", path, e);
        return -1;
    }
    w->enc = avcodec_alloc_context3(c);
    w->pkt = av_packet_alloc();
    w->st = avformat_new_stream(w->oc, NULL);
    if (!w->enc || !w->pkt || !w->st) {
        snprintf(why, why_len, "video %s: out of memory", path);
        writer_free(w);
        return -1;
    }
    w->enc->width = width;
    w->enc->height = height;
    w->enc->pix_fmt = AV_PIX_FMT_GRAY8;
    w->enc->time_base = tb;
    w->enc->level = 3;
    w->enc->thread_count = p->threads;
    w->enc->thread_type = FF_THREAD_SLICE;
    if (w->oc->oformat->flags & AVFMT_GLOBALHEADER) w->enc->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    AVDictionary *opt = NULL;
    char sl[16];
    snprintf(sl, sizeof sl, "%d", p->slices);
    av_dict_set(&opt, "slices", sl, 0);
    av_dict_set(&opt, "slicecrc", "1", 0);
    av_dict_set(&opt, "coder", p->range_coder ? "range_def" : "rice", 0);
    e = avcodec_open2(w->enc, c, &opt);
    av_dict_free(&opt);
    if (e < 0) {
        av_why(why, why_len, "cannot open the FFV1 encoder for", path, e);
        writer_free(w);
        return -1;
    }
    avcodec_parameters_from_context(w->st->codecpar, w->enc);
    w->st->time_base = tb;
    if ((e = avio_open(&w->oc->pb, path, AVIO_FLAG_WRITE)) < 0) {
        av_why(why, why_len, "cannot write", path, e);
        writer_free(w);
        return -1;
    }
    if ((e = avformat_write_header(w->oc, NULL)) < 0) {
        av_why(why, why_len, "cannot write the header of", path, e);
        writer_free(w);
        return -1;
    }
    return 0;
}

/* Sends frame (NULL: flush) and writes every packet the encoder has ready. */
static int writer_put(av_writer *w, AVFrame *frame, char *why, size_t why_len)
{
    int e = avcodec_send_frame(w->enc, frame);
    if (e < 0) {
        av_why(why, why_len, "FFV1 encoder refused a frame for", w->path, e);
        return -1;
    }
    for (;;) {
        e = avcodec_receive_packet(w->enc, w->pkt);
        if (e == AVERROR(EAGAIN) || e == AVERROR_EOF) return 0;
        if (e < 0) {
            av_why(why, why_len, "FFV1 encoder failed for", w->path, e);
            return -1;
        }
        /* One frame period each: Matroska's duration then covers the last frame too, and readers
           that count frames from it (OpenCV) find them all. */
        if (w->pkt->duration <= 0) w->pkt->duration = 1;
        av_packet_rescale_ts(w->pkt, w->enc->time_base, w->st->time_base);
        w->pkt->stream_index = w->st->index;
        if ((e = av_interleaved_write_frame(w->oc, w->pkt)) < 0) {
            av_why(why, why_len, "cannot write a frame to", w->path, e);
            return -1;
        }
    }
}

static int writer_finish(av_writer *w, char *why, size_t why_len)
{
    int e = av_write_trailer(w->oc);
    if (e < 0) {
        av_why(why, why_len, "cannot finish", w->path, e);
        return -1;
    }
    int io = w->oc->pb ? w->oc->pb->error : 0;
    if (w->oc->pb) avio_closep(&w->oc->pb);
    if (io < 0) {
        av_why(why, why_len, "cannot write", w->path, io);
        return -1;
    }
    return 0;
}

static int fsync_path(const char *path, int dir)
{
    int fd = open(path, dir ? O_RDONLY | O_DIRECTORY : O_RDONLY);
    if (fd < 0) return -1;
    int rc = fsync(fd);
    close(fd);
    return rc;
}

static void dir_of(const char *path, char *out, size_t len)
{
    snprintf(out, len, "%s", path);
    char *s = strrchr(out, '/');
    if (!s) snprintf(out, len, ".");
    else if (s == out) s[1] = '\0';
    else *s = '\0';
}

static int check_params(const trial_transcode_params *p, char *why, size_t why_len)
{
    static const int ok_slices[] = {4, 6, 9, 12, 16, 24, 30};
    int sl = 0;
    for (size_t k = 0; k < sizeof ok_slices / sizeof ok_slices[0]; k++) sl |= p->slices == ok_slices[k];
    if (p->threads < 1 || p->threads > 16 || !sl) {
        snprintf(why, why_len, "transcode: threads %d (1..16) or slices %d (4, 6, 9, 12, 16, 24 or 30) out of range",
                 p->threads, p->slices);
        return -1;
    }
    if (p->crop_w < 0 || p->crop_h < 0 || p->crop_x < 0 || p->crop_y < 0 || (p->crop_w > 0 && p->crop_h <= 0)) {
        snprintf(why, why_len, "transcode: crop %dx%d+%d+%d is not a region", p->crop_w, p->crop_h, p->crop_x,
                 p->crop_y);
        return -1;
    }
    return 0;
}

/* The encode pass: raw -> part, cropped; frames counted in res. */
static int encode_pass(const char *raw_path, const char *part, const trial_transcode_params *p, int crop[4],
                       trial_transcode_result *res, char *why, size_t why_len)
{
    av_reader r;
    if (reader_open(&r, raw_path, why, why_len)) return -1;
    AVStream *ist = r.fmt->streams[r.stream];
    AVRational rate = ist->avg_frame_rate.num > 0 ? ist->avg_frame_rate : ist->r_frame_rate;
    AVRational tb = rate.num > 0 && rate.den > 0 ? av_inv_q(rate) : (AVRational){1, 60};
    int W = r.dec->width, H = r.dec->height;
    if (p->crop_w > 0) {
        crop[0] = p->crop_x, crop[1] = p->crop_y, crop[2] = p->crop_w, crop[3] = p->crop_h;
    } else {
        crop[0] = 0, crop[1] = 0, crop[2] = W, crop[3] = H;
    }
    if (W <= 0 || H <= 0 || crop[0] + crop[2] > W || crop[1] + crop[3] > H) {
        snprintf(why, why_len, "transcode: crop %dx%d+%d+%d does not fit %s's %dx%d frames", crop[2], crop[3],
                 crop[0], crop[1], raw_path, W, H);
        reader_close(&r);
        return -1;
    }
    res->width = crop[2];
    res->height = crop[3];
    av_writer w;
    if (writer_open(&w, part, crop[2], crop[3], tb, p, why, why_len)) {
        reader_close(&r);
        return -1;
    }
    AVFrame *out = av_frame_alloc();
    int rc = -1;
    if (!out) {
        snprintf(why, why_len, "transcode: out of memory");
        goto done;
    }
    out->format = AV_PIX_FMT_GRAY8;
    out->width = crop[2];
    out->height = crop[3];
    if (av_frame_get_buffer(out, 0) < 0) {
        snprintf(why, why_len, "transcode: out of memory for a %dx%d frame", crop[2], crop[3]);
        goto done;
    }
    for (long f = 0;; f++) {
        if (p->cancel && *p->cancel) {
            snprintf(why, why_len, "transcode stopped at frame %ld (the daemon is shutting down)", f);
            goto done;
        }
        int h = reader_next(&r, f, why, why_len);
        if (h < 0) goto done;
        if (h == 0) break;
        if (r.frm->width != W || r.frm->height != H) {
            snprintf(why, why_len, "video %s: frame %ld is %dx%d, the first was %dx%d", raw_path, f, r.frm->width,
                     r.frm->height, W, H);
            goto done;
        }
        /* The encoder may still hold the previous frame's buffer (slice threads): write a fresh one. */
        if (av_frame_make_writable(out) < 0) {
            snprintf(why, why_len, "transcode: out of memory");
            goto done;
        }
        for (int y = 0; y < crop[3]; y++)
            memcpy(out->data[0] + (size_t)y * (size_t)out->linesize[0],
                   r.frm->data[0] + (size_t)(crop[1] + y) * (size_t)r.frm->linesize[0] + (size_t)crop[0],
                   (size_t)crop[2]);
        if (f == p->corrupt_frame) out->data[0][0] ^= 1;
        out->pts = f;
        if (writer_put(&w, out, why, why_len)) goto done;
        res->frames = f + 1;
        if (p->on_frame) p->on_frame(p->on_frame_user, f);
    }
    if (writer_put(&w, NULL, why, why_len) || writer_finish(&w, why, why_len)) goto done;
    rc = 0;
done:
    av_frame_free(&out);
    writer_free(&w);
    reader_close(&r);
    return rc;
}

int trial_transcode_run(const char *raw_path, const char *out_path, const trial_transcode_params *pp,
                        trial_transcode_result *res, char *why, size_t why_len)
{
    trial_transcode_params p = pp ? *pp : trial_transcode_params_default();
    trial_transcode_result rr;
    memset(&rr, 0, sizeof rr);
    if (!res) res = &rr;
    memset(res, 0, sizeof *res);
    if (check_params(&p, why, why_len)) return -1;
    struct stat sb;
    if (stat(raw_path, &sb) != 0) {
        snprintf(why, why_len, "transcode: %s: %s", raw_path, strerror(errno));
        return -1;
    }
    res->raw_bytes = (int64_t)sb.st_size;
    char part[1100];
    if (snprintf(part, sizeof part, "%s.part", out_path) >= (int)sizeof part) {
        snprintf(why, why_len, "transcode: the output path is too long");
        return -1;
    }
    av_log_set_level(AV_LOG_ERROR);
    int crop[4];
    double t0 = now_s();
    int rc = encode_pass(raw_path, part, &p, crop, res, why, why_len);
    double t1 = now_s();
    res->encode_s = t1 - t0;
    if (rc == 0 && fsync_path(part, 0) != 0) {
        snprintf(why, why_len, "transcode: cannot sync %s: %s", part, strerror(errno));
        rc = -1;
    }
    long n = 0;
    if (rc == 0) {
        char sub[400];
        rc = trial_transcode_compare(raw_path, part, crop, &n, sub, sizeof sub);
        if (rc == 0 && n != res->frames) {
            snprintf(sub, sizeof sub, "verify: %ld frames compared, %ld encoded", n, res->frames);
            rc = -1;
        }
        if (rc) snprintf(why, why_len, "%s", sub);
    }
    res->verify_s = now_s() - t1;
    if (rc == 0 && res->frames == 0) {
        snprintf(why, why_len, "transcode: %s holds no frame", raw_path);
        rc = -1;
    }
    char dir[1100];
    dir_of(out_path, dir, sizeof dir);
    if (rc == 0 && rename(part, out_path) != 0) {
        snprintf(why, why_len, "transcode: cannot rename %s to %s: %s", part, out_path, strerror(errno));
        rc = -1;
    }
    if (rc) {
        unlink(part);
        return -1;
    }
    fsync_path(dir, 1);
    if (stat(out_path, &sb) == 0) res->out_bytes = (int64_t)sb.st_size;
    /* The raw file goes only now: the output is verified, renamed and synced. */
    if (!p.keep_raw) {
        if (unlink(raw_path) == 0) {
            res->raw_removed = 1;
            fsync_path(dir, 1);
        }
    }
    return 0;
}
