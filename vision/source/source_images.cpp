// source_images.cpp: frames from a numbered image sequence ("dir/frame_%04d.png").
//
// The sequence ends at the first missing number. A file that exists but cannot be decoded is
// reported as damage (VIS_ERR_FORMAT naming the file), not as the end. Time stamps are the index
// over an assumed 1 fps since still images carry none (callers with a real rate rescale).
#include "source.hpp"
#include "image_header.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <cstring>
#include <sys/stat.h>

namespace vis {
namespace {

bool pattern_ok(const char *p)
{
    // Exactly one integer conversion (%d, %0Nd, %Nd) and no other conversion.
    int conv = 0;
    for (const char *c = p; *c; c++) {
        if (*c != '%')
            continue;
        if (c[1] == '%') {
            c++;
            continue;
        }
        c++;
        while (*c >= '0' && *c <= '9')
            c++;
        if (*c != 'd')
            return false;
        conv++;
    }
    return conv == 1;
}

class ImageSource : public Source {
public:
    std::string pattern;
    int next = 0, first = 0;

    std::string name(int i) const
    {
        char buf[4096];
        std::snprintf(buf, sizeof buf, pattern.c_str(), i);
        return buf;
    }
    vis_status read(cv::Mat &grey, double &t_s, vis_error *err) override
    {
        const std::string f = name(next);
        struct stat st;
        if (stat(f.c_str(), &st) != 0)
            return fail(err, VIS_ERR_END, "image sequence ends before %s", f.c_str());
        if (image_size_check(f.c_str(), err) != VIS_OK)
            return err ? err->code : VIS_ERR_TOO_LARGE;
        cv::Mat m = cv::imread(f, cv::IMREAD_GRAYSCALE);
        if (m.empty())
            return fail(err, VIS_ERR_FORMAT, "image %s is damaged or not an image", f.c_str());
        m.copyTo(grey);
        t_s = (double)(next - first);
        next++;
        return VIS_OK;
    }
};

}  // namespace

Source *source_images_open(const char *pattern, int first, vis_error *err)
{
    if (!pattern_ok(pattern) || std::strlen(pattern) > 4000) {
        fail(err, VIS_ERR_ARG, "image pattern \"%s\" needs exactly one %%d-style conversion",
             pattern);
        return nullptr;
    }
    if (first < 0) {
        fail(err, VIS_ERR_ARG, "image sequence: first index %d < 0", first);
        return nullptr;
    }
    ImageSource *s = new ImageSource;
    s->pattern = pattern;
    s->first = s->next = first;
    struct stat st;
    if (stat(s->name(first).c_str(), &st) != 0) {
        fail(err, VIS_ERR_IO, "image sequence: first image %s not found", s->name(first).c_str());
        delete s;
        return nullptr;
    }
    return s;
}

}  // namespace vis
