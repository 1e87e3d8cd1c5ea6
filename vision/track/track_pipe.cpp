// track_pipe.cpp: frames tracked on several cores with exactly the serial results (vis_track_pipe).
//
// Why this can be exact: the tracker follows frame k from frame k-1's curve, but every
// refresh_frames-th frame (and wherever the caller resets) it forgets that curve and acquires the
// ribbon from scratch. What happens from such a frame on depends only on the frames, so a fresh
// copy of the tracker started there computes, bit for bit, what the serial tracker computes. The
// pipe cuts the frames at those points into stretches and hands each stretch to the first idle
// worker; results come back in push order. The first stretch goes on from the caller's tracker as
// it was at create (its previous curve, its count towards the next refresh), so a pipe may take
// over a serial loop at any frame. The frames move through a ring of slots by swapping
// cv::Mat headers, never by copying pixels.
//
// Locking: one mutex for the ring's counters, the stretches and every slot's `done` flag. A slot's
// frame and result belong to the caller between pop and push, to the worker of its stretch between
// push and `done`, to the caller again from `done` on; each side touches them without the lock only
// while they are its own.
#include "tracker_impl.hpp"

#include <algorithm>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <new>
#include <system_error>
#include <thread>
#include <vector>

namespace {

constexpr size_t MAX_HELD = 256;  // frames the pipe holds at most (1280 x 720 grey: 236 MB)

struct Slot {
    cv::Mat frame;
    double shear = 0;
    bool done = false;
    vis_status status = VIS_OK;
    vis_error err{};
    vis_measure m{};
    std::vector<double> uv;  // the centreline, (u, v) pairs
    int worker = -1;         // who tracked it
};

// Frames [first, end) tracked from a reset by one worker; end is open until the next stretch starts.
struct Stretch {
    uint64_t first = 0;
    uint64_t end = UINT64_MAX;
    int worker = -1;          // -1: not taken yet
    bool from_start = false;  // goes on from the caller's tracker as it was at create, not reset
};

}  // namespace

struct vis_track_pipe {
    vis_tracker *owner = nullptr;  // the caller's tracker: state back at free
    vis::TrackerPtr start;         // its state at create
    uint64_t first_len = 0;        // frames the first stretch runs before the owner's next refresh
    int refresh = 0;
    std::vector<vis::TrackerPtr> trk;  // one per worker (asked for)
    int n_workers = 0;                                            // threads that started
    std::vector<std::thread> threads;
    std::vector<Slot> ring;
    std::deque<Stretch> stretches;   // not yet finished by their worker, oldest first
    uint64_t pushed = 0, popped = 0;
    uint64_t in_stretch = 0;         // frames pushed into the newest stretch
    int last_worker = -1;            // worker of the last frame popped (the serial state's holder)
    bool stop = false;
    int workers_waiting = 0;         // workers asleep on cv_work
    bool caller_waiting = false;     // the caller asleep on cv_done
    std::mutex mu;
    std::condition_variable cv_work, cv_done;  // new frames or stop; a frame done
    // Wait on cv_work, counted, so that a push wakes nobody when every worker is busy.
    template <class Pred> void work_wait(std::unique_lock<std::mutex> &lk, Pred pred)
    {
        workers_waiting++;
        cv_work.wait(lk, pred);
        workers_waiting--;
    }

    Slot &slot(uint64_t i) { return ring[i % ring.size()]; }
    void run(int w);
};

void vis_track_pipe::run(int w)
{
    vis_tracker *t = trk[(size_t)w].get();
    std::unique_lock<std::mutex> lk(mu);
    for (;;) {
        Stretch *s = nullptr;
        work_wait(lk, [&] {
            if (stop)
                return true;
            for (Stretch &x : stretches)
                if (x.worker < 0) {
                    s = &x;
                    return true;
                }
            return false;
        });
        if (stop)
            return;
        s->worker = w;
        const uint64_t first = s->first;
        // The deque may move its elements as stretches are added: keep the index, not the pointer.
        auto end_of = [&] {
            for (const Stretch &x : stretches)
                if (x.first == first)
                    return x.end;
            return first;  // not reached: a stretch leaves only when its worker is done
        };
        const bool from_start = s->from_start;
        lk.unlock();
        bool ready = true;
        try {
            if (from_start)
                vis::tracker_take_state(t, start.get());
            else
                vis_tracker_reset(t);
        } catch (const std::exception &) {  // out of memory copying the curve: every frame says so
            ready = false;
        }
        lk.lock();
        for (uint64_t j = first;; j++) {
            if (!(stop || j < pushed || j >= end_of()))
                work_wait(lk, [&] { return stop || j < pushed || j >= end_of(); });
            if (stop)
                return;
            if (j >= end_of())
                break;
            Slot &sl = slot(j);
            lk.unlock();
            try {
                if (!ready)
                    throw std::bad_alloc();
                vis_frame f;
                f.mat = sl.frame;  // shares the pixels, no copy
                sl.status = vis_tracker_process(t, &f, sl.shear, &sl.m, &sl.err);
                const size_t n = vis_tracker_curve(t, nullptr, 0);
                sl.uv.resize(2 * n);
                vis_tracker_curve(t, sl.uv.data(), n);
            } catch (const std::exception &e) {  // the curve's copy: out of memory
                sl.uv.clear();
                sl.status = vis::fail(&sl.err, VIS_ERR_NOMEM, "track pipe: %s", e.what());
            }
            vis::tracker_drop_views(t);
            sl.worker = w;
            lk.lock();
            sl.done = true;
            if (caller_waiting)
                cv_done.notify_one();
        }
        stretches.erase(std::find_if(stretches.begin(), stretches.end(),
                                     [&](const Stretch &x) { return x.first == first; }));
    }
}

extern "C" vis_track_pipe *vis_track_pipe_create(vis_tracker *t, int threads, vis_error *err)
{
    if (!t || threads < 0 || threads > 64) {
        vis::fail(err, VIS_ERR_ARG, "vis_track_pipe_create: NULL tracker or threads outside 0..64");
        return nullptr;
    }
    VIS_GUARD(err, nullptr, {
        std::unique_ptr<vis_track_pipe> p(new vis_track_pipe);
        p->owner = t;
        p->refresh = vis::tracker_refresh_frames(t);
        p->start.reset(vis::tracker_fresh_copy(t));
        vis::tracker_take_state(p->start.get(), t);
        const long done = vis::tracker_since_reset(t);
        p->first_len = p->refresh == 0 ? UINT64_MAX : done < p->refresh ? (uint64_t)(p->refresh - done) : 0;
        int n = threads ? threads : (int)std::max(1u, std::thread::hardware_concurrency());
        if (p->refresh == 0)
            n = 1;  // one stretch: nothing to share
        const size_t cap = p->refresh ? (size_t)(n + 1) * (size_t)p->refresh : 16;
        p->ring.resize(std::min<size_t>(MAX_HELD, std::max<size_t>(16, cap)));
        // Stretches in flight are bounded by the ring: more workers would wait with a tracker each.
        if (p->refresh > 0)
            n = (int)std::min<size_t>((size_t)n, p->ring.size() / (size_t)p->refresh + 1);
        for (int w = 0; w < n; w++)
            p->trk.emplace_back(vis::tracker_fresh_copy(t));
        p->threads.reserve((size_t)n);
        for (int w = 0; w < n; w++) {
            vis_track_pipe *raw = p.get();
            try {
                p->threads.emplace_back([raw, w] { raw->run(w); });
            } catch (const std::system_error &) {
                if (w == 0) {
                    vis_track_pipe_free(p.release());
                    throw;
                }
                break;  // no more threads to be had: the stretches go to the workers there are
            }
        }
        p->n_workers = (int)p->threads.size();
        vis::ok(err);
        return p.release();
    })
}

extern "C" void vis_track_pipe_free(vis_track_pipe *p)
{
    if (!p)
        return;
    {
        std::lock_guard<std::mutex> lk(p->mu);
        p->stop = true;
    }
    p->cv_work.notify_all();
    for (std::thread &th : p->threads)
        th.join();
    // Every frame handed back: the worker of the last one holds what the serial loop ends in.
    if (p->popped == p->pushed && p->last_worker >= 0)
        vis::tracker_take_state(p->owner, p->trk[(size_t)p->last_worker].get());
    else if (p->popped != p->pushed)
        vis_tracker_reset(p->owner);
    delete p;
}

extern "C" size_t vis_track_pipe_capacity(const vis_track_pipe *p) { return p ? p->ring.size() : 0; }

extern "C" size_t vis_track_pipe_held(const vis_track_pipe *p)
{
    if (!p)
        return 0;
    std::lock_guard<std::mutex> lk(const_cast<vis_track_pipe *>(p)->mu);
    return (size_t)(p->pushed - p->popped);
}

extern "C" int vis_track_pipe_workers(const vis_track_pipe *p) { return p ? p->n_workers : 0; }

extern "C" vis_status vis_track_pipe_push(vis_track_pipe *p, vis_frame *f, double shear_mm, int reset,
                                          vis_error *err)
{
    if (!p || !f || f->mat.empty())
        return vis::fail(err, VIS_ERR_ARG, "vis_track_pipe_push: NULL pipe or empty frame");
    if (!vis::finite(shear_mm))
        return vis::fail(err, VIS_ERR_ARG, "vis_track_pipe_push: shear_mm is not finite");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        std::unique_lock<std::mutex> lk(p->mu);
        if (p->pushed - p->popped >= p->ring.size())
            return vis::fail(err, VIS_ERR_ARG, "vis_track_pipe_push: the pipe is full (%zu frames): pop first",
                             p->ring.size());
        const bool first = !p->stretches.empty() && p->stretches.back().from_start;
        const uint64_t limit = first ? p->first_len : p->refresh > 0 ? (uint64_t)p->refresh : UINT64_MAX;
        const bool fresh = p->pushed == 0 || reset || p->in_stretch >= limit;
        if (fresh) {
            // Only the newest stretch is open, and a worker erases its stretch only once closed.
            if (!p->stretches.empty() && p->stretches.back().end == UINT64_MAX)
                p->stretches.back().end = p->pushed;
            Stretch s;
            s.first = p->pushed;
            s.from_start = p->pushed == 0 && !reset && p->first_len > 0;
            p->stretches.push_back(s);
            p->in_stretch = 0;
        }
        Slot &sl = p->slot(p->pushed);
        // The slot is the caller's (popped, or never used): swap the pixels in, hand its old
        // buffer back.
        cv::swap(sl.frame, f->mat);
        sl.shear = shear_mm;
        sl.done = false;
        sl.worker = -1;
        p->pushed++;
        p->in_stretch++;
        const bool wake = p->workers_waiting > 0;
        lk.unlock();
        if (wake)
            p->cv_work.notify_all();
        vis::ok(err);
        return VIS_OK;
    })
}

extern "C" vis_status vis_track_pipe_pop(vis_track_pipe *p, int wait, vis_measure *m, double *uv, size_t max_uv,
                                         size_t *n_uv, vis_frame *frame, vis_error *err)
{
    if (!p || !m)
        return vis::fail(err, VIS_ERR_ARG, "vis_track_pipe_pop: NULL pipe or measure");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        std::unique_lock<std::mutex> lk(p->mu);
        if (p->popped == p->pushed)
            return vis::fail(err, VIS_ERR_END, "the pipe holds no frame");
        Slot &sl = p->slot(p->popped);
        if (!sl.done) {
            if (!wait)
                return vis::fail(err, VIS_ERR_NOT_FOUND, "frame %llu is not tracked yet",
                                 (unsigned long long)p->popped);
            p->caller_waiting = true;
            p->cv_done.wait(lk, [&] { return sl.done; });
            p->caller_waiting = false;
        }
        // Which worker holds the serial state once this frame is the last: the one that tracked it.
        p->last_worker = sl.worker;
        lk.unlock();
        *m = sl.m;
        const size_t n = sl.uv.size() / 2;
        if (uv)
            std::copy(sl.uv.begin(), sl.uv.begin() + 2 * (ptrdiff_t)std::min(n, max_uv), uv);
        if (n_uv)
            *n_uv = n;
        if (frame)
            cv::swap(sl.frame, frame->mat);
        const vis_status st = sl.status;
        if (err)
            *err = sl.err;
        lk.lock();
        p->popped++;
        return st;
    })
}
