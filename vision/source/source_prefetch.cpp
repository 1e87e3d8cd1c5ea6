// source_prefetch.cpp: a frame source that decodes ahead on its own thread.
//
// Why: the tracker is sequential (frame k follows frame k-1's curve), so what can run beside it is
// the decoding. This wrapper owns another source and a thread that reads it into a ring of `depth`
// frames while the caller tracks the ones already there; read() hands them out in order with the
// inner source's own status and message (an end, or damage after frame N, arrives after the frames
// before it, as from the inner source). The frames, their order and their times are exactly the
// inner source's, so anything computed from them is identical to the serial run. Wall time becomes
// about max(decode, track) per frame instead of their sum.
#include "source.hpp"

#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace vis {

namespace {

class PrefetchSource : public Source {
public:
    PrefetchSource(Source *inner, size_t depth)
        : inner_(inner), slots_(depth), count_(inner->frame_count()), fps_(inner->fps())
    {
        worker_ = std::thread([this] { run(); });
    }
    ~PrefetchSource() override
    {
        {
            std::lock_guard<std::mutex> lk(mu_);
            stop_ = true;
        }
        cv_.notify_all();
        worker_.join();
        delete inner_;
    }
    vis_status read(cv::Mat &grey, double &t_s, vis_error *err) override
    {
        std::unique_lock<std::mutex> lk(mu_);
        if (done_reading_ && tail_ == head_)
            return fail(err, last_status_, "%s", last_msg_.c_str());
        cv_.wait(lk, [&] { return head_ > tail_ || done_reading_; });
        if (head_ == tail_)
            return fail(err, last_status_, "%s", last_msg_.c_str());
        Slot &s = slots_[tail_ % slots_.size()];
        t_s = s.t;
        lk.unlock();
        // Copied, not swapped: the caller (the tracker) may still hold views of its old buffer.
        // Only this thread reads slot k until tail_ moves past it.
        s.frame.copyTo(grey);
        lk.lock();
        tail_++;
        lk.unlock();
        cv_.notify_all();
        return VIS_OK;
    }
    int frame_count() const override { return count_; }
    double fps() const override { return fps_; }

private:
    struct Slot {
        cv::Mat frame;
        double t = 0;
    };
    void run()
    {
        for (;;) {
            size_t k;
            {
                std::unique_lock<std::mutex> lk(mu_);
                cv_.wait(lk, [&] { return stop_ || head_ - tail_ < slots_.size(); });
                if (stop_)
                    return;
                k = head_ % slots_.size();
            }
            // Only this thread touches slot k until head_ moves past it.
            vis_error e{};
            vis_status st;
            double t = 0;
            try {
                st = inner_->read(slots_[k].frame, t, &e);
            } catch (const std::exception &x) {
                st = VIS_ERR_INTERNAL;
                snprintf(e.message, sizeof e.message, "decoder thread: %s", x.what());
            } catch (...) {
                st = VIS_ERR_INTERNAL;
                snprintf(e.message, sizeof e.message, "decoder thread: unknown exception");
            }
            {
                std::lock_guard<std::mutex> lk(mu_);
                if (st == VIS_OK) {
                    slots_[k].t = t;
                    head_++;
                } else {
                    last_status_ = st;
                    last_msg_ = e.message;
                    done_reading_ = true;
                }
            }
            cv_.notify_all();
            if (st != VIS_OK)
                return;
        }
    }

    Source *inner_;
    std::vector<Slot> slots_;
    int count_;
    double fps_;
    std::mutex mu_;
    std::condition_variable cv_;
    size_t head_ = 0, tail_ = 0;  // frames decoded, frames handed out
    bool stop_ = false, done_reading_ = false;
    vis_status last_status_ = VIS_ERR_END;
    std::string last_msg_;
    std::thread worker_;
};

}  // namespace

Source *source_prefetch_wrap(Source *inner, size_t depth)
{
    if (!inner)
        return nullptr;
    try {
        return new PrefetchSource(inner, depth < 2 ? 2 : depth);
    } catch (...) {
        delete inner;
        throw;
    }
}

}  // namespace vis
