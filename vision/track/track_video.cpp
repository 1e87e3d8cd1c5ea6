// track_video.cpp: a whole video decoded and tracked on every core, results identical to the serial
// loop (vis_track_video).
//
// threads = 1 is the plain serial loop (the reference and the one-core figure). Otherwise the
// stretches between the tracker's refresh points (vis_track_params.refresh_frames) go to separate
// cores, each tracked from a fresh copy of the tracker, so every frame's vis_measure is bit for bit
// the serial one (test_vision_track_video checks it) and `t` ends in the serial loop's state:
//   - raw grey recordings (Y800, the trials' own): every worker reads the file itself, passing
//     over the other workers' stretches as packets (demuxed, not copied), so each frame is read
//     and tracked on one core with its pixels in that core's cache. Handing frames decoded on one
//     thread to trackers on others cost 0.16 ms of CPU a 1280 x 720 frame in moving them between
//     cores (a third of the tracking), measured with vis_track_pipe;
//   - every other format (FFV1: decoding is what costs) decodes ahead on one thread
//     (source_prefetch.cpp, plus libavcodec's own threads) into vis_track_pipe (track_pipe.cpp).
#include "source.hpp"
#include "tracker_impl.hpp"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace {

// Frame i's shear (0 past the table).
double shear_of(const double *shear_mm, size_t n_shear, size_t i) { return shear_mm && i < n_shear ? shear_mm[i] : 0.0; }

vis_status serial(vis_source *src, vis_tracker *t, const double *shear_mm, size_t n_shear, vis_measure *out,
                  size_t max_frames, size_t *n_frames, vis_frame *f, vis_error *err)
{
    for (size_t i = 0; i < max_frames; i++) {
        const vis_status s = vis_source_read(src, f, nullptr, err);
        if (s == VIS_ERR_END)
            return VIS_OK;
        if (s != VIS_OK)
            return s;
        const vis_status rc = vis_tracker_process(t, f, shear_of(shear_mm, n_shear, i), &out[i], err);
        if (rc != VIS_OK)
            return rc;
        *n_frames = i + 1;
    }
    return VIS_OK;
}

vis_status piped(vis_source *src, vis_track_pipe *p, const double *shear_mm, size_t n_shear, vis_measure *out,
                 size_t max_frames, size_t *n_frames, vis_frame *f, vis_error *err)
{
    size_t pushed = 0;
    vis_status tracked = VIS_OK;  // the first frame the tracker failed on ends everything
    // One result out (waiting for it when `wait`); false when none was taken.
    auto take = [&](int wait) {
        const vis_status s = vis_track_pipe_pop(p, wait, &out[*n_frames], nullptr, 0, nullptr, nullptr, err);
        if (s == VIS_ERR_NOT_FOUND || s == VIS_ERR_END)
            return false;
        if (s != VIS_OK) {
            tracked = s;
            return false;
        }
        (*n_frames)++;
        return true;
    };
    vis_status read = VIS_OK;
    vis_error read_err{};
    while (tracked == VIS_OK && pushed < max_frames) {
        if (vis_track_pipe_held(p) >= vis_track_pipe_capacity(p) && !take(1))
            break;
        const vis_status s = vis_source_read(src, f, nullptr, &read_err);
        if (s == VIS_ERR_END)
            break;
        if (s != VIS_OK) {
            read = s;
            break;
        }
        if ((tracked = vis_track_pipe_push(p, f, shear_of(shear_mm, n_shear, pushed), 0, err)) != VIS_OK)
            break;
        pushed++;
        while (take(0)) {
        }
    }
    // The frames still in the pipe precede the end or the damage: they come out, up to a frame the
    // tracker fails on (what follows that one is never handed out, as in the serial loop).
    while (tracked == VIS_OK && take(1)) {
    }
    if (tracked != VIS_OK)
        return tracked;
    if (read != VIS_OK && err)
        *err = read_err;
    return read;
}

// Raw grey recordings: `n` workers, each with its own reader and tracker copy, taking the stretches
// in order. The first frame that ends or fails the stream (or whose tracking fails) bounds the
// result: everything before it was tracked (every earlier stretch was taken before it).
struct Readers {
    std::mutex mu;
    uint64_t next = 0;              // next stretch to hand out
    uint64_t stop_at = UINT64_MAX;  // first frame that ended or failed
    vis_status stop_status = VIS_ERR_END;
    vis_error stop_err{};
    void failed(uint64_t i, vis_status s, const vis_error &e)
    {
        std::lock_guard<std::mutex> lk(mu);
        if (i < stop_at) {
            stop_at = i;
            stop_status = s;
            stop_err = e;
        }
    }
};

vis_status readers(const char *path, vis::Source *first_src, vis_tracker *t, int n, const double *shear_mm,
                   size_t n_shear, vis_measure *out, size_t max_frames, size_t *n_frames, vis_error *err)
{
    const uint64_t K = (uint64_t)vis::tracker_refresh_frames(t);
    Readers sh;
    std::vector<vis::TrackerPtr> trk;
    std::vector<int64_t> last(n, -1);  // the last frame each worker tracked
    std::vector<uint64_t> at(n, 0);    // the frame each worker is reading or passing over
    for (int w = 0; w < n; w++)
        trk.emplace_back(vis::tracker_fresh_copy(t));
    auto work_frames = [&](int w, vis::Source *src) {
        vis_error e{};
        uint64_t pos = 0;  // the frame src hands out next
        cv::Mat grey;
        vis_frame f;
        for (;;) {
            uint64_t a;
            {
                std::lock_guard<std::mutex> lk(sh.mu);
                a = sh.next++ * K;
                if (a >= sh.stop_at || a >= max_frames)
                    return;
            }
            // Passed over packet by packet: OpenCV 4.6's seek (CAP_PROP_POS_FRAMES) on raw
            // packets does not land on the frame asked for (tried: results differed).
            for (; pos < a; pos++) {
                at[(size_t)w] = pos;
                const vis_status s = src->skip(&e);
                if (s != VIS_OK) {
                    sh.failed(pos, s, e);
                    return;
                }
            }
            const uint64_t b = std::min<uint64_t>(a + K, max_frames);
            for (uint64_t i = a; i < b; i++) {
                at[(size_t)w] = i;
                double ts = 0;
                vis_status s = src->read(grey, ts, &e);
                pos++;
                if (s == VIS_OK) {
                    if (i == a)  // only once its frame is read: a worker at the end keeps its state
                        vis_tracker_reset(trk[(size_t)w].get());
                    f.mat = grey;
                    s = vis_tracker_process(trk[(size_t)w].get(), &f, shear_of(shear_mm, n_shear, i),
                                            &out[i], &e);
                    f.mat.release();
                    vis::tracker_drop_views(trk[(size_t)w].get());
                }
                if (s != VIS_OK) {
                    sh.failed(i, s, e);
                    return;
                }
                last[(size_t)w] = (int64_t)i;
            }
        }
    };
    // Nothing thrown may leave a thread (OpenCV's allocations): it ends the frames at the one that
    // worker was on.
    auto work = [&](int w, vis::Source *src) {
        try {
            work_frames(w, src);
        } catch (const std::exception &x) {
            vis_error e{};
            vis::fail(&e, VIS_ERR_INTERNAL, "video %s: %s", path, x.what());
            sh.failed(at[(size_t)w], VIS_ERR_INTERNAL, e);
        }
    };
    std::vector<std::unique_ptr<vis::Source>> src;
    src.emplace_back(first_src);
    for (int w = 1; w < n; w++) {
        vis_error e{};
        vis::Source *s = vis::source_video_open(path, &e);
        if (!s || !s->cheap_skip()) {  // no more readers to be had (descriptors?): fewer workers
            delete s;
            break;
        }
        src.emplace_back(s);
    }
    n = (int)src.size();
    std::vector<std::thread> th;
    th.reserve((size_t)n);
    for (int w = 1; w < n; w++) {
        try {
            th.emplace_back(work, w, src[(size_t)w].get());
        } catch (const std::system_error &) {
            break;  // no more threads to be had: the stretches go to the workers there are
        }
    }
    work(0, src[0].get());
    for (std::thread &x : th)
        x.join();
    *n_frames = (size_t)std::min<uint64_t>(sh.stop_at, max_frames);
    for (int w = 0; w < n && *n_frames > 0; w++)
        if (last[(size_t)w] == (int64_t)*n_frames - 1)
            vis::tracker_take_state(t, trk[(size_t)w].get());
    if (sh.stop_status != VIS_ERR_END && sh.stop_at < max_frames) {
        vis_tracker_reset(t);
        if (err)
            *err = sh.stop_err;
        return sh.stop_status;
    }
    return VIS_OK;
}

}  // namespace

static vis_status track_video(const char *path, vis_tracker *t, const double *shear_mm, size_t n_shear, int threads,
                              vis_measure *out, size_t max_frames, size_t *n_frames, vis_error *err);

extern "C" vis_status vis_track_video(const char *path, vis_tracker *t, const double *shear_mm,
                                      size_t n_shear, int threads, vis_measure *out, size_t max_frames,
                                      size_t *n_frames, vis_error *err)
{
    if (!path || !t || !out || !n_frames || threads < 0 || threads > 64)
        return vis::fail(err, VIS_ERR_ARG, "vis_track_video: NULL argument or threads outside 0..64");
    *n_frames = 0;
    vis_tracker_reset(t);
    const vis_status rc = track_video(path, t, shear_mm, n_shear, threads, out, max_frames, n_frames, err);
    if (rc != VIS_OK)
        vis_tracker_reset(t);  // after a failure the tracker starts afresh, whichever way it ran
    return rc;
}

static vis_status track_video(const char *path, vis_tracker *t, const double *shear_mm, size_t n_shear, int threads,
                              vis_measure *out, size_t max_frames, size_t *n_frames, vis_error *err)
{
    const int n = threads ? threads : (int)std::max(1u, std::thread::hardware_concurrency());
    if (n > 1 && vis::tracker_refresh_frames(t) > 0) {
        vis_status rc = VIS_OK;
        VIS_GUARD(err, VIS_ERR_INTERNAL, {
            vis::Source *first = vis::source_video_open(path, err);
            if (!first)
                return err ? err->code : VIS_ERR_IO;
            if (first->cheap_skip())
                rc = readers(path, first, t, n, shear_mm, n_shear, out, max_frames, n_frames, err);
            else {
                delete first;
                rc = VIS_ERR_NOT_FOUND;  // decoded formats: the pipe below
            }
        })
        if (rc != VIS_ERR_NOT_FOUND) {
            if (rc == VIS_OK)
                vis::ok(err);
            return rc;
        }
    }
    vis_source *src = threads == 1 ? vis_source_open_video(path, err) : vis_source_open_video_prefetch(path, err);
    if (!src)
        return err ? err->code : VIS_ERR_IO;
    vis_frame *f = vis_frame_alloc(8, 8, 1, err);
    vis_track_pipe *p = f && threads != 1 ? vis_track_pipe_create(t, threads, err) : nullptr;
    vis_status rc = !f ? VIS_ERR_NOMEM : threads != 1 && !p ? (err ? err->code : VIS_ERR_INTERNAL) : VIS_OK;
    if (rc == VIS_OK)
        rc = p ? piped(src, p, shear_mm, n_shear, out, max_frames, n_frames, f, err)
               : serial(src, t, shear_mm, n_shear, out, max_frames, n_frames, f, err);
    vis_track_pipe_free(p);
    vis_frame_free(f);
    vis_source_close(src);
    if (rc == VIS_OK)
        vis::ok(err);
    return rc;
}
