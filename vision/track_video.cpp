// track_video.cpp: a whole video decoded and tracked on every core, results identical to the serial
// loop (vis_track_video).
//
// The tracker is sequential by nature: frame k is followed from frame k-1's curve, so two frames
// cannot be tracked at once without changing the results. What runs in parallel is everything
// else: decoding runs on its own thread (and libavcodec's threads) into a ring of frame buffers
// while the calling thread tracks, so the wall time is about max(decode, track) instead of their
// sum. The tracker sees exactly the frames, in exactly the order, of the serial loop, so each
// frame's vis_measure is bit for bit the serial one (test_vision_track_video checks it).
// With threads = 1 it is the serial loop itself (the reference and the one-core figure).
#include "vis_internal.hpp"

#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace {

struct Ring {
    std::mutex mu;
    std::condition_variable cv;
    std::vector<vis_frame *> slot;
    std::vector<vis_status> st;
    std::vector<std::string> msg;
    size_t head = 0, tail = 0;  // frames produced, consumed
    bool stop = false;
};

}  // namespace

extern "C" vis_status vis_track_video(const char *path, vis_tracker *t, const double *shear_mm,
                                      size_t n_shear, int threads, vis_measure *out, size_t max_frames,
                                      size_t *n_frames, vis_error *err)
{
    if (!path || !t || !out || !n_frames || threads < 0 || threads > 64)
        return vis::fail(err, VIS_ERR_ARG, "vis_track_video: NULL argument or threads outside 0..64");
    *n_frames = 0;
    if (threads == 0)
        threads = (int)std::max(1u, std::thread::hardware_concurrency());
    vis_source *src = vis_source_open_video(path, err);
    if (!src)
        return err ? err->code : VIS_ERR_IO;
    auto shear_at = [&](size_t i) { return shear_mm && i < n_shear ? shear_mm[i] : 0.0; };
    if (threads == 1) {
        vis_frame *f = vis_frame_alloc(8, 8, 1, err);
        vis_status rc = f ? VIS_OK : VIS_ERR_NOMEM;
        for (size_t i = 0; rc == VIS_OK && i < max_frames; i++) {
            const vis_status s = vis_source_read(src, f, nullptr, err);
            if (s == VIS_ERR_END)
                break;
            if (s != VIS_OK) {
                rc = s;
                break;
            }
            rc = vis_tracker_process(t, f, shear_at(i), &out[i], err);
            if (rc == VIS_OK)
                *n_frames = i + 1;
        }
        vis_frame_free(f);
        vis_source_close(src);
        if (rc == VIS_OK)
            vis::ok(err);
        return rc;
    }
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        const size_t K = 16;
        Ring ring;
        ring.slot.assign(K, nullptr);
        ring.st.assign(K, VIS_OK);
        ring.msg.assign(K, std::string());
        for (size_t k = 0; k < K; k++)
            if (!(ring.slot[k] = vis_frame_alloc(8, 8, 1, err))) {
                for (auto *f : ring.slot)
                    vis_frame_free(f);
                vis_source_close(src);
                return VIS_ERR_NOMEM;
            }
        std::thread dec([&] {
            for (size_t i = 0; i < max_frames; i++) {
                {
                    std::unique_lock<std::mutex> lk(ring.mu);
                    ring.cv.wait(lk, [&] { return ring.stop || ring.head - ring.tail < K; });
                    if (ring.stop)
                        return;
                }
                const size_t k = i % K;
                vis_error e{};
                vis_status s;
                try {
                    s = vis_source_read(src, ring.slot[k], nullptr, &e);
                } catch (...) {
                    s = VIS_ERR_INTERNAL;
                    snprintf(e.message, sizeof e.message, "decoder thread: exception");
                }
                {
                    std::lock_guard<std::mutex> lk(ring.mu);
                    ring.st[k] = s;
                    ring.msg[k] = e.message;
                    ring.head++;
                }
                ring.cv.notify_all();
                if (s != VIS_OK)
                    return;
            }
        });
        vis_status rc = VIS_OK;
        for (size_t i = 0; i < max_frames; i++) {
            const size_t k = i % K;
            vis_status s;
            {
                std::unique_lock<std::mutex> lk(ring.mu);
                ring.cv.wait(lk, [&] { return ring.head > i; });
                s = ring.st[k];
                if (s != VIS_OK && s != VIS_ERR_END)
                    vis::fail(err, s, "%s", ring.msg[k].c_str());
            }
            if (s == VIS_ERR_END)
                break;
            if (s != VIS_OK) {
                rc = s;
                break;
            }
            rc = vis_tracker_process(t, ring.slot[k], shear_at(i), &out[i], err);
            {
                std::lock_guard<std::mutex> lk(ring.mu);
                ring.tail = i + 1;
            }
            ring.cv.notify_all();
            if (rc != VIS_OK)
                break;
            *n_frames = i + 1;
        }
        {
            std::lock_guard<std::mutex> lk(ring.mu);
            ring.stop = true;
        }
        ring.cv.notify_all();
        dec.join();
        for (auto *f : ring.slot)
            vis_frame_free(f);
        vis_source_close(src);
        if (rc == VIS_OK)
            vis::ok(err);
        return rc;
    })
}
