/* trial_capture.c: capture thread, frame ring and recorder thread of a live trial
 * (see trial_capture.h).
 *
 * Layout: `info` is a ring of TRIAL_INFO_SLOTS frame records (every captured frame, dropped ones
 * included), read in order by the runner. `slot` is the ring of `slots` pixel frames; pixel
 * sequence numbers count only frames that got a slot. Capture fills pixel seq `fill` (chosen under
 * the lock, filled outside it) only when the recorder is done with seq fill - slots; the runner
 * copies a published seq p under the lock when p > fill - slots (not the slot being filled). */
#include "trial_capture.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "trial_clock_map.h"

#define TRIAL_INFO_SLOTS 8192 /* frame records kept for the runner (2 min 16 s at 60 fps) */

typedef struct rec_meta {
    long index;
    uint64_t camera_id;
    double camera_t_s, host_t_s, t_s;
} rec_meta;

typedef struct info_rec {
    trial_frame_info fi;
    long pseq; /* pixel seq, -1 = dropped */
} info_rec;

struct trial_capture {
    trial_capture_params p;
    vis_source *src;
    pthread_t cap_thread, rec_thread;
    int cap_started, rec_started;
    pthread_mutex_t lock;
    pthread_cond_t cond;           /* any counter moved */
    /* under lock */
    long info_head;                /* frames published */
    long trk_seq;                  /* next frame for the runner */
    long fill;                     /* pixel seq being filled (or next to fill) */
    long pix_head;                 /* pixel frames published */
    long rec_seq;                  /* next pixel frame for the recorder */
    int stop;                      /* capture asked to stop */
    int warm_done;                 /* the clock map's warm-up is over: frames are published */
    int cap_ended;                 /* the capture thread has ended */
    char cap_why[256];             /* why it ended, "" = asked to */
    trial_capture_counts counts;
    char rec_why[256];             /* the recorder's first failure */
    /* storage */
    info_rec *info;
    vis_frame **slot;
    rec_meta *meta;
    vis_frame *scratch;
    trial_clock_map map;
    int *loss_ring;                /* per published frame: lost + incomplete just before it */
    long loss_n, loss_sum;         /* frames in the ring, their sum */
    trial_video *video;
    FILE *times;
};

trial_capture_params trial_capture_params_default(void)
{
    trial_capture_params p;
    memset(&p, 0, sizeof p);
    p.slots = 64;
    p.track_max_lag = 16;
    p.track_max_age_s = 0.1;
    p.frame_timeout_s = 1.0;
    p.fps = 60.0;
    p.warmup_s = 1.0;
    p.max_loss_fraction = 0.25;
    p.loss_window = 60;
    return p;
}

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* FNV-1a over 64-bit words (and the tail bytes) of every row: equal frames, equal hashes. */
static uint64_t frame_hash(vis_frame *f)
{
    const int w = vis_frame_width(f), h = vis_frame_height(f);
    const size_t stride = vis_frame_stride(f), rowb = (size_t)w * (size_t)vis_frame_channels(f);
    const uint8_t *d = vis_frame_data(f);
    uint64_t x = 14695981039346656037ull;
    for (int y = 0; y < h; y++) {
        const uint8_t *r = d + (size_t)y * stride;
        size_t i = 0;
        for (; i + 8 <= rowb; i += 8) {
            uint64_t v;
            memcpy(&v, r + i, 8);
            x = (x ^ v) * 1099511628211ull;
        }
        for (; i < rowb; i++) x = (x ^ r[i]) * 1099511628211ull;
    }
    return x;
}

static void *capture_main(void *arg)
{
    trial_capture *c = arg;
    vis_error ve;
    double warm_t0 = NAN;
    uint64_t prev_hash = 0, prev_id = 0;
    long same_run = 0;
    for (;;) {
        pthread_mutex_lock(&c->lock);
        if (c->stop) {
            pthread_mutex_unlock(&c->lock);
            break;
        }
        int have_slot = c->fill - c->rec_seq < c->p.slots;
        long pseq = have_slot ? c->fill : -1;
        pthread_mutex_unlock(&c->lock);
        vis_frame *dst = have_slot ? c->slot[pseq % c->p.slots] : c->scratch;
        vis_frame_meta m;
        memset(&m, 0, sizeof m);
        memset(&ve, 0, sizeof ve);
        vis_status st = vis_source_read_meta(c->src, dst, &m, &ve);
        if (st != VIS_OK) {
            pthread_mutex_lock(&c->lock);
            if (!c->stop)
                snprintf(c->cap_why, sizeof c->cap_why, "%s", ve.message[0] ? ve.message : vis_status_str(st));
            pthread_mutex_unlock(&c->lock);
            break;
        }
        double t = trial_clock_map_add(&c->map, m.camera_t_s, m.host_t_s);
        if (!c->warm_done) {
            /* The clock map's warm-up: frames only teach the map, until they span warmup_s of the
             * camera's time (a camera without times, or on the host's clock, needs none). */
            if (!isfinite(warm_t0)) warm_t0 = m.camera_t_s;
            int over = !isfinite(m.camera_t_s) || c->map.identity || m.camera_t_s - warm_t0 >= c->p.warmup_s;
            pthread_mutex_lock(&c->lock);
            c->counts.warmup++;
            c->counts.lost += m.lost_before; /* the camera's losses count from its first frame */
            c->counts.incomplete += m.incomplete;
            if (over) {
                c->warm_done = 1;
                pthread_cond_broadcast(&c->cond);
            }
            pthread_mutex_unlock(&c->lock);
            continue;
        }
        const uint64_t hash = frame_hash(dst);
        same_run = same_run > 0 && (hash == prev_hash || m.frame_id == prev_id) ? same_run + 1 : 1;
        prev_hash = hash;
        prev_id = m.frame_id;
        pthread_mutex_lock(&c->lock);
        /* The link's quality over the last loss_window frames. */
        const int bad = (int)(m.lost_before + m.incomplete);
        if (c->loss_ring) {
            const int W = c->p.loss_window;
            if (c->loss_n >= W) c->loss_sum -= c->loss_ring[c->loss_n % W];
            c->loss_ring[c->loss_n % W] = bad;
            c->loss_sum += bad;
            c->loss_n++;
            const long seen = (c->loss_n < W ? c->loss_n : W) + c->loss_sum;
            if (c->loss_n >= W && (double)c->loss_sum > c->p.max_loss_fraction * (double)seen) {
                snprintf(c->cap_why, sizeof c->cap_why,
                         "the camera's frames are lost or incomplete: %ld of the last %ld (limit %.0f%%)",
                         c->loss_sum, seen, 100.0 * c->p.max_loss_fraction);
                c->counts.lost += m.lost_before;
                c->counts.incomplete += m.incomplete;
                pthread_mutex_unlock(&c->lock);
                break;
            }
        }
        if (c->info_head - c->trk_seq >= TRIAL_INFO_SLOTS) {
            snprintf(c->cap_why, sizeof c->cap_why,
                     "the trial loop is %d frames behind the camera: frame records would be overwritten",
                     TRIAL_INFO_SLOTS);
            pthread_mutex_unlock(&c->lock);
            break;
        }
        info_rec *r = &c->info[c->info_head % TRIAL_INFO_SLOTS];
        memset(r, 0, sizeof *r);
        r->fi.index = c->info_head;
        r->fi.camera_id = m.frame_id;
        r->fi.camera_t_s = m.camera_t_s;
        r->fi.host_t_s = m.host_t_s;
        r->fi.t_s = t;
        r->fi.dropped = !have_slot;
        r->fi.video_index = have_slot ? pseq : -1;
        r->fi.lost_before = m.lost_before;
        r->fi.incomplete = m.incomplete;
        r->fi.same_run = same_run;
        r->pseq = pseq;
        c->counts.captured++;
        c->counts.lost += m.lost_before;
        c->counts.incomplete += m.incomplete;
        if (have_slot) {
            rec_meta *rm = &c->meta[pseq % c->p.slots];
            rm->index = c->info_head;
            rm->camera_id = m.frame_id;
            rm->camera_t_s = m.camera_t_s;
            rm->host_t_s = m.host_t_s;
            rm->t_s = t;
            c->fill++;
            c->pix_head = c->fill;
        } else {
            c->counts.dropped++;
        }
        c->counts.offset_s = trial_clock_map_offset(&c->map, m.camera_t_s);
        c->counts.drift = trial_clock_map_drift(&c->map);
        c->counts.identity_clock = c->map.identity;
        c->info_head++;
        pthread_cond_broadcast(&c->cond);
        pthread_mutex_unlock(&c->lock);
    }
    pthread_mutex_lock(&c->lock);
    c->cap_ended = 1;
    pthread_cond_broadcast(&c->cond);
    pthread_mutex_unlock(&c->lock);
    return NULL;
}

static void *record_main(void *arg)
{
    trial_capture *c = arg;
    char why[256];
    for (;;) {
        pthread_mutex_lock(&c->lock);
        while (c->rec_seq >= c->pix_head && !c->cap_ended) pthread_cond_wait(&c->cond, &c->lock);
        if (c->rec_seq >= c->pix_head) { /* capture over and everything written */
            pthread_mutex_unlock(&c->lock);
            break;
        }
        long seq = c->rec_seq;
        int failed = c->rec_why[0] != '\0';
        pthread_mutex_unlock(&c->lock);
        /* The slot is ours until rec_seq moves: capture does not fill it. */
        const vis_frame *f = c->slot[seq % c->p.slots];
        const rec_meta *rm = &c->meta[seq % c->p.slots];
        int ok = 1;
        if (!failed && c->video && trial_video_add(c->video, f, why, sizeof why)) ok = 0;
        if (ok && !failed && c->times &&
            fprintf(c->times, "%ld,%ld,%llu,%.9f,%.9f,%.9f\n", seq, rm->index, (unsigned long long)rm->camera_id,
                    rm->camera_t_s, rm->host_t_s, rm->t_s) < 0) {
            snprintf(why, sizeof why, "frame-times file: write failed: %s", strerror(errno));
            ok = 0;
        }
        double lat = mono_s() - rm->host_t_s;
        pthread_mutex_lock(&c->lock);
        if (!ok && !c->rec_why[0]) snprintf(c->rec_why, sizeof c->rec_why, "%s", why);
        if (ok && !failed) {
            c->counts.recorded++;
            if (lat > c->counts.max_capture_to_record_s) c->counts.max_capture_to_record_s = lat;
        }
        c->rec_seq++;
        pthread_cond_broadcast(&c->cond);
        pthread_mutex_unlock(&c->lock);
    }
    return NULL;
}

static void free_storage(trial_capture *c)
{
    if (c->slot)
        for (int k = 0; k < c->p.slots; k++) vis_frame_free(c->slot[k]);
    free(c->slot);
    free(c->meta);
    free(c->info);
    free(c->loss_ring);
    vis_frame_free(c->scratch);
}

trial_capture *trial_capture_start(vis_source *src, const trial_capture_params *p, char *why, size_t why_len)
{
    if (!src || !p || p->slots < 4 || p->track_max_lag < 1 || p->track_max_lag >= p->slots ||
        !(p->frame_timeout_s > 0.0) || !(p->fps > 0.0) || !(p->track_delay_s >= 0.0) || !(p->track_max_age_s >= 0.0) ||
        !(p->warmup_s >= 0.0 && p->warmup_s <= 60.0) || !(p->max_loss_fraction >= 0.0 && p->max_loss_fraction < 1.0) ||
        (p->max_loss_fraction > 0.0 && (p->loss_window < 1 || p->loss_window > 100000))) {
        snprintf(why, why_len, "capture: need a source, slots >= 4, 1 <= track_max_lag < slots, positive timeout "
                               "and fps, a warm-up of 0-60 s, a loss fraction in [0, 1) over 1-100000 frames");
        return NULL;
    }
    trial_capture *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(why, why_len, "capture: out of memory");
        return NULL;
    }
    c->p = *p;
    c->src = src;
    c->warm_done = !(p->warmup_s > 0.0);
    pthread_mutex_init(&c->lock, NULL);
    pthread_cond_init(&c->cond, NULL);
    trial_clock_map_init(&c->map);
    vis_error ve = {0};
    c->info = calloc(TRIAL_INFO_SLOTS, sizeof *c->info);
    c->slot = calloc((size_t)p->slots, sizeof *c->slot);
    c->meta = calloc((size_t)p->slots, sizeof *c->meta);
    c->scratch = vis_frame_alloc(16, 16, 1, &ve);
    if (p->max_loss_fraction > 0.0) c->loss_ring = calloc((size_t)p->loss_window, sizeof *c->loss_ring);
    int ok = c->info && c->slot && c->meta && c->scratch && (c->loss_ring || !(p->max_loss_fraction > 0.0));
    for (int k = 0; ok && k < p->slots; k++) ok = (c->slot[k] = vis_frame_alloc(16, 16, 1, &ve)) != NULL;
    if (!ok) {
        snprintf(why, why_len, "capture: out of memory for %d frames", p->slots);
        goto fail;
    }
    if (p->video_path) {
        c->video = trial_video_open(p->video_path, p->roi, p->fps, why, why_len);
        if (!c->video) goto fail;
        char tpath[4200];
        snprintf(tpath, sizeof tpath, "%s.frames.csv", p->video_path);
        c->times = fopen(tpath, "w");
        if (!c->times) {
            snprintf(why, why_len, "frame-times file %s: %s", tpath, strerror(errno));
            goto fail;
        }
        fprintf(c->times, "video_frame,capture_index,camera_id,camera_t_s,host_t_s,t_s\n");
    }
    if (pthread_create(&c->rec_thread, NULL, record_main, c) != 0) {
        snprintf(why, why_len, "capture: the recorder thread could not start");
        goto fail;
    }
    c->rec_started = 1;
    if (pthread_create(&c->cap_thread, NULL, capture_main, c) != 0) {
        snprintf(why, why_len, "capture: the capture thread could not start");
        pthread_mutex_lock(&c->lock);
        c->cap_ended = 1;
        pthread_cond_broadcast(&c->cond);
        pthread_mutex_unlock(&c->lock);
        pthread_join(c->rec_thread, NULL);
        goto fail;
    }
    c->cap_started = 1;
    /* Nothing is published (and the caller moves nothing) before the clock map has warmed up. */
    pthread_mutex_lock(&c->lock);
    while (!c->warm_done && !c->cap_ended) pthread_cond_wait(&c->cond, &c->lock);
    int warm = c->warm_done;
    if (!warm) snprintf(why, why_len, "camera: %s", c->cap_why[0] ? c->cap_why : "capture stopped");
    pthread_mutex_unlock(&c->lock);
    if (!warm) {
        /* nothing recorded: no empty video left behind */
        char w2[256], tpath[4200];
        trial_capture_stop(c, NULL, w2, sizeof w2);
        if (p->video_path) {
            snprintf(tpath, sizeof tpath, "%s.frames.csv", p->video_path);
            unlink(p->video_path);
            unlink(tpath);
        }
        return NULL;
    }
    return c;
fail:
    if (c->times) fclose(c->times);
    if (c->video) trial_video_close(c->video, why + strlen(why), 0);
    free_storage(c);
    pthread_cond_destroy(&c->cond);
    pthread_mutex_destroy(&c->lock);
    free(c);
    return NULL;
}

int trial_capture_next(trial_capture *c, vis_frame *out, trial_frame_info *info, char *why, size_t why_len)
{
    struct timespec dl;
    clock_gettime(CLOCK_REALTIME, &dl);
    double t = (double)dl.tv_sec + 1e-9 * (double)dl.tv_nsec + c->p.frame_timeout_s;
    dl.tv_sec = (time_t)t;
    dl.tv_nsec = (long)((t - (double)dl.tv_sec) * 1e9);
    pthread_mutex_lock(&c->lock);
    while (c->trk_seq >= c->info_head && !c->cap_ended) {
        if (pthread_cond_timedwait(&c->cond, &c->lock, &dl) == ETIMEDOUT && c->trk_seq >= c->info_head) {
            pthread_mutex_unlock(&c->lock);
            snprintf(why, why_len, "camera: no frame for %.2f s", c->p.frame_timeout_s);
            return -1;
        }
    }
    if (c->trk_seq >= c->info_head) {
        snprintf(why, why_len, "camera: %s", c->cap_why[0] ? c->cap_why : "capture stopped");
        pthread_mutex_unlock(&c->lock);
        return -1;
    }
    const info_rec *r = &c->info[c->trk_seq % TRIAL_INFO_SLOTS];
    *info = r->fi;
    long lag = c->info_head - c->trk_seq;
    int safe = r->pseq >= 0 && r->pseq > c->fill - c->p.slots;
    int old = c->p.track_max_age_s > 0.0 && mono_s() - r->fi.host_t_s > c->p.track_max_age_s;
    info->skip = !info->dropped && (lag > c->p.track_max_lag || old || !safe);
    if (!info->dropped && !info->skip) {
        const vis_frame *src = c->slot[r->pseq % c->p.slots];
        vis_error ve = {0};
        if (vis_frame_copy(src, out, &ve) != VIS_OK) {
            pthread_mutex_unlock(&c->lock);
            snprintf(why, why_len, "capture: %s", ve.message);
            return -1;
        }
    }
    if (info->skip) c->counts.skipped++;
    c->trk_seq++;
    pthread_mutex_unlock(&c->lock);
    if (!info->dropped && !info->skip && c->p.track_delay_s > 0.0) {
        struct timespec ts = {(time_t)c->p.track_delay_s,
                              (long)((c->p.track_delay_s - (double)(time_t)c->p.track_delay_s) * 1e9)};
        nanosleep(&ts, NULL);
    }
    return 0;
}

void trial_capture_get_counts(trial_capture *c, trial_capture_counts *out)
{
    pthread_mutex_lock(&c->lock);
    *out = c->counts;
    pthread_mutex_unlock(&c->lock);
}

int trial_capture_stop(trial_capture *c, trial_capture_counts *out, char *why, size_t why_len)
{
    if (!c) return 0;
    pthread_mutex_lock(&c->lock);
    c->stop = 1;
    pthread_mutex_unlock(&c->lock);
    if (c->cap_started) pthread_join(c->cap_thread, NULL);
    if (c->rec_started) pthread_join(c->rec_thread, NULL);
    int rc = 0;
    why[0] = '\0';
    if (c->rec_why[0]) {
        snprintf(why, why_len, "%s", c->rec_why);
        rc = -1;
    }
    if (c->times && fclose(c->times) != 0 && rc == 0) {
        snprintf(why, why_len, "frame-times file: close failed: %s", strerror(errno));
        rc = -1;
    }
    char w2[256] = "";
    if (c->video && trial_video_close(c->video, w2, sizeof w2) < 0 && rc == 0) {
        snprintf(why, why_len, "%s", w2);
        rc = -1;
    }
    if (out) *out = c->counts;
    free_storage(c);
    pthread_cond_destroy(&c->cond);
    pthread_mutex_destroy(&c->lock);
    free(c);
    return rc;
}
