// tracker.cpp: the tracker object and its per-frame pipeline (vis_tracker_process).
//
// Stages, in order (each in its own file, see tracker_impl.hpp):
//   1. frame checks: unreadable, too dark, saturated, noise (no structure) -> a reason, not an error;
//   2. clamp points: from the calibration; the right one moves toward the principal point as the
//      shear carries it away from the camera (magnification D / (D + shear));
//   3. polarity fixed, or decided once and then kept;
//   4. guide: the previous frame's smooth curve, traced on the raw (polarity-folded) grey levels in
//      its bounding box, since each profile brings its own background level; or, when there is no
//      previous curve or following it fails or its length jumps (first frame, snap-through,
//      recovery after a lost frame, a loop forming), a fresh acquisition on the black-hat/top-hat
//      ridge signal of the whole frame (which removes lighting, clamps and large clutter): walks
//      along the ridge from either clamp (path_walk.cpp: loops, crossings, tangents past
//      vertical) and, if neither measures, the geodesic path between the clamps; every candidate
//      is refined and measured and the best kept (pick_better: measured, then quality, then the
//      longer of two comparable ones, since every wrong path is a shortcut);
//   5. tracer passes (wide band, then narrow; three from a fresh path, two from the previous curve)
//      refining the centreline to sub-pixel; then the samples in bends are moved back onto the
//      centreline where the band's cross-sections are oblique to the curve (section_bias.cpp);
//   6. metric curve: undistortion (if the calibration has intrinsics), then depth correction: the
//      point at arc fraction xi is assumed at depth y = shear (3 xi^2 - 2 xi^3) (clamped ends keep
//      their tangent along x, so the shear profile is flat at both clamps), or at the depth of the
//      caller's profile (a prediction's shape, depth_profile.cpp), and its pixel's ray is
//      intersected with the plane at that depth, camera tilt included (view_model.cpp);
//   6b. when no attempt measured and one was refused only for a tight bend with the ribbon's face
//      showing (where cross-section centroids slide inward), its bends are measured with the
//      silhouette model (bend_model.cpp) and it is measured again (refine_bends);
//   7. local smooth fit, Delta Z, A, quality, reason. With the length known, the measured
//      (projected) length must lie within the bounds the shear allows (projected_length_bounds);
//      quality falls outside them and beyond 8% the frame is lost, never a confident shortcut.
//      Nothing ribbon-like along any path is NO_RIBBON.
// All buffers live in the tracker and are reused from frame to frame.
#include "tracker_impl.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace {
// One way of measuring a frame (following the previous curve, or a fresh acquisition).
struct Attempt {
    vis_reason reason = VIS_REASON_LOST;
    double quality = 0;
    double valid_frac = 0;          // share of the arc with a clear ridge
    double length_rel = 0;          // measured length / known length - 1 (0 when unknown)
    double bend_rel = 0;            // tightest radius of curvature / the ridge's median width
    bool bend_refused = false;      // refused by the bend check (bend_rel, the face, A)
    bool ran = false;               // tried on this frame
    bool bends_modelled = false;    // tight bends measured by the silhouette model (bend_model.cpp)
    bool followed = false;          // traced along the previous frame's curve on the grey frame
    bool bridged = false;           // refused for bridging a gap off the ridge (bridged_points)
    double len_px = 0;              // the guide's length, px (the samples' arc positions run over it)
    std::vector<vis::TraceSample> samples;  // the tracer's last pass
    vis_measure m{};
    std::vector<vis::Pt> curve_px;  // smooth centreline, pixels
    std::vector<vis::Pt> curve_mm;  // the same in the plane, mm from the left clamp point
    std::vector<vis::Pt> traced_px; // the fit's input: clamp point, valid samples, clamp point, px
};
}  // namespace

struct vis_tracker {
    vis_track_params p;
    vis_calib c;
    int polarity = 0;                // 0 undecided, 1 dark, 2 light
    std::vector<vis::Pt> prev;       // previous smooth centreline, pixels (empty: none)
    double prev_length = 0;          // its measured length, mm
    std::vector<vis::Pt> curve;      // last smooth centreline, pixels (for overlays)
    std::vector<vis::Pt> traced;     // the traced points that curve was fitted to, pixels
    cv::Mat work, sig;
    vis::Workspace ws;               // per-frame buffers, reused
    Attempt att[4];                  // following; walks from the left, from the right; geodesic
    std::vector<vis::Pt> path;       // geodesic path scratch
    std::vector<cv::Point3d> obj3;   // redistortion scratch
    std::vector<cv::Point2d> img2;
    cv::Mat trace_img;               // what the tracer samples: sig, or the grey frame itself
    bool trace_invert = false;       // sample 255 - value (grey frame, dark ribbon)
    cv::Mat frame_grey;              // this frame's grey view, what followed curves are traced on
    bool frame_dark = false;         // its polarity (the ribbon darker than its surroundings)
    cv::Size size;
    vis::DepthProfile depth;         // depth along the arc this frame (the base, or a library's shape)
    vis::DepthProfile base_depth;    // the profile of vis_tracker_set_depth_profile (default cubic)
    long since_reset = 0;            // vis_tracker_process calls since made or reset (refresh_frames)
    vis::DepthLibrary library;       // a prediction's shapes (vis_tracker_set_depth_library)
    Attempt redo;                    // the best attempt measured again with the library's depth
    Attempt bent;                    // a refused attempt with its tight bends modelled
    vis::BendModel bend_model;
    std::vector<vis::Pt> bend_win, bend_others, bend_out;
};

extern "C" vis_track_params vis_track_params_default(void)
{
    vis_track_params p;
    p.length_mm = 0.0;
    p.polarity = VIS_POLARITY_AUTO;
    p.band_px = 12.0;
    p.ribbon_max_px = 8.0;
    p.step_px = 1.0;
    p.end_margin_px = 3.0;
    p.fit_window = 0.08;
    p.end_window = 0.11;
    p.min_contrast = 12.0;
    p.min_quality = 0.3;
    p.min_bend_ratio = 2.0;
    p.refresh_frames = 100;
    return p;
}

// A strip twisted under shear turns its face to the camera: at phi 60 (creases at 60 deg) the
// middle section shows most of its 5 mm face late in the shear, 12.5 px at the mock camera's
// 2.49 px/mm, and the default 8 px refused that ridge over 40 frames ("ribbon occluded").
extern "C" vis_track_params vis_track_params_for_ribbon(double width_mm, double px_per_mm)
{
    vis_track_params p = vis_track_params_default();
    const double face_px = width_mm * px_per_mm;
    if (!vis::finite(face_px) || !(width_mm > 0.0) || !(px_per_mm > 0.0))
        return p;
    p.ribbon_max_px = std::min(100.0, std::max(p.ribbon_max_px, std::ceil(face_px + 2.0)));
    p.band_px = std::min(100.0, std::max(p.band_px, 1.5 * p.ribbon_max_px));
    return p;
}

static bool track_params_valid(const vis_track_params &p, vis_error *err)
{
    if (!vis::finite(p.length_mm) || p.length_mm < 0 || !vis::finite(p.band_px) || p.band_px < 1 ||
        p.band_px > 100 || !vis::finite(p.ribbon_max_px) || p.ribbon_max_px < 1 ||
        p.ribbon_max_px > 100 || !vis::finite(p.step_px) || p.step_px < 0.25 || p.step_px > 20 ||
        !vis::finite(p.end_margin_px) || p.end_margin_px < 0 || p.end_margin_px > 200 ||
        !vis::finite(p.fit_window) || p.fit_window <= 0 || p.fit_window > 0.25 ||
        !vis::finite(p.end_window) || p.end_window <= 0 || p.end_window > 0.5 ||
        !vis::finite(p.min_contrast) || p.min_contrast < 0 || p.min_contrast > 255 ||
        !vis::finite(p.min_quality) || p.min_quality < 0 || p.min_quality > 1 ||
        !vis::finite(p.min_bend_ratio) || p.min_bend_ratio < 0 || p.min_bend_ratio > 10 ||
        (p.polarity != VIS_POLARITY_AUTO && p.polarity != VIS_POLARITY_DARK &&
         p.polarity != VIS_POLARITY_LIGHT)) {
        vis::fail(err, VIS_ERR_ARG,
                  "track params: need length_mm >= 0, 1 <= band_px <= 100, 1 <= ribbon_max_px <= 100, "
                  "0.25 <= step_px <= 20, 0 <= end_margin_px <= 200, 0 < fit_window <= 0.25, 0 < end_window <= 0.5, "
                  "0 <= min_contrast <= 255, 0 <= min_quality <= 1, 0 <= min_bend_ratio <= 10, a known polarity");
        return false;
    }
    if (p.refresh_frames < 0 || p.refresh_frames > 100000) {
        vis::fail(err, VIS_ERR_ARG, "track params: refresh_frames %d is outside 0..100000", p.refresh_frames);
        return false;
    }
    return true;
}

extern "C" vis_tracker *vis_tracker_create(const vis_track_params *p, const vis_calib *c,
                                           vis_error *err)
{
    if (!p || !c) {
        vis::fail(err, VIS_ERR_ARG, "vis_tracker_create: NULL params or calibration");
        return nullptr;
    }
    if (!track_params_valid(*p, err) || vis_calib_check(c, err) != VIS_OK)
        return nullptr;
    VIS_GUARD(err, nullptr, {
        vis_tracker *t = new vis_tracker;
        t->p = *p;
        t->c = *c;
        if (p->polarity == VIS_POLARITY_DARK)
            t->polarity = 1;
        else if (p->polarity == VIS_POLARITY_LIGHT)
            t->polarity = 2;
        vis::ok(err);
        return t;
    })
}

extern "C" void vis_tracker_free(vis_tracker *t) { delete t; }

extern "C" vis_status vis_tracker_set_depth_profile(vis_tracker *t, const double *frac, const double *depth_rel,
                                                    size_t n, vis_error *err)
{
    if (!t)
        return vis::fail(err, VIS_ERR_ARG, "vis_tracker_set_depth_profile: NULL tracker");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        std::string why;
        if (!t->base_depth.set(frac, depth_rel, n, why))
            return vis::fail(err, VIS_ERR_ARG, "%s", why.c_str());
        t->depth = t->base_depth;
        vis::ok(err);
        return VIS_OK;
    })
}

extern "C" vis_status vis_tracker_set_depth_library(vis_tracker *t, const vis_depth_library *lib, vis_error *err)
{
    if (!t)
        return vis::fail(err, VIS_ERR_ARG, "vis_tracker_set_depth_library: NULL tracker");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        std::string why;
        if (!t->library.set(lib, why))
            return vis::fail(err, VIS_ERR_ARG, "%s", why.c_str());
        vis::ok(err);
        return VIS_OK;
    })
}

extern "C" void vis_tracker_reset(vis_tracker *t)
{
    if (!t)
        return;
    t->prev.clear();
    t->prev_length = 0;
    t->curve.clear();
    t->traced.clear();
    if (t->p.polarity == VIS_POLARITY_AUTO)
        t->polarity = 0;
    t->depth = t->base_depth;
    t->since_reset = 0;
}

vis_tracker *vis::tracker_fresh_copy(const vis_tracker *t)
{
    vis_tracker *c = new vis_tracker(*t);
    // cv::Mat copies share pixels: give the copy its own scratch images.
    c->work = cv::Mat();
    c->sig = cv::Mat();
    c->trace_img = cv::Mat();
    c->frame_grey = cv::Mat();
    vis_tracker_reset(c);
    return c;
}

void vis::tracker_take_state(vis_tracker *into, const vis_tracker *from)
{
    into->prev = from->prev;
    into->prev_length = from->prev_length;
    into->curve = from->curve;
    into->polarity = from->polarity;
    into->depth = from->depth;
    into->since_reset = from->since_reset;
    into->size = from->size;
}

void vis::tracker_drop_views(vis_tracker *t)
{
    t->trace_img = cv::Mat();
    t->frame_grey = cv::Mat();
}

int vis::tracker_refresh_frames(const vis_tracker *t) { return t->p.refresh_frames; }

long vis::tracker_since_reset(const vis_tracker *t) { return t->since_reset; }

static void measure_clear(vis_measure *m, vis_reason r)
{
    m->reason = r;
    m->dz = 0;
    m->a = 0;
    m->quality = 0;
    m->length_mm = 0;
    m->mid_px[0] = m->mid_px[1] = 0;
    m->residual_px = 0;
}

extern "C" void vis_tracker_skip(vis_tracker *t, vis_measure *out)
{
    if (out)
        measure_clear(out, VIS_REASON_UNREADABLE);
    (void)t;  // the previous curve stays the best guide for the next frame
}

namespace {

// The points of a tracker's curve or traced samples into uv (at most max of them); their count.
size_t copy_points(const std::vector<vis::Pt> &pts, double *uv, size_t max)
{
    for (size_t i = 0; uv && i < max && i < pts.size(); i++) {
        uv[2 * i] = pts[i].x;
        uv[2 * i + 1] = pts[i].y;
    }
    return pts.size();
}

}  // namespace

extern "C" size_t vis_tracker_curve(const vis_tracker *t, double *uv, size_t max)
{
    return t ? copy_points(t->curve, uv, max) : 0;
}

extern "C" size_t vis_tracker_samples(const vis_tracker *t, double *uv, size_t max)
{
    return t ? copy_points(t->traced, uv, max) : 0;
}

namespace {

using vis::Pt;

// Relative distance of the measured length outside the bounds the known length allows: up to
// LENGTH_SLACK costs nothing (the fit rounds the ends and creases: -1.6% on the unsheared DER ribbon
// at 640 x 480), quality halves at twice that, and beyond LENGTH_TOL the frame is not measured.
const double LENGTH_SLACK = 0.03;
const double LENGTH_TOL = 0.08;

struct Geometry {
    vis::ViewModel vm;                 // image <-> plane model (principal point, scale, distance, tilt)
    Pt left, right;                    // clamp points in the image at this frame's shear, pixels
    double shear;                      // mm
    const vis::DepthProfile *depth;    // depth / shear along the projected arc, for this frame
};

// Depth (mm, away from the camera) of the centreline at projected arc fraction xi: by default the
// shear profile of a ribbon clamped flat at both ends, shear * (3 xi^2 - 2 xi^3); the caller's
// profile when it gave one (depth_profile.cpp).
double depth_at(const Geometry &g, double xi) { return g.shear * g.depth->at(xi); }

// Bounds on the length of the centreline's x-z projection (what the tracker measures) for a ribbon
// of length l whose depth goes from 0 at the left clamp to `shear` at the right one, monotonically:
// with y' = dy/ds, the projection is the integral of sqrt(1 - y'^2) with the integral of |y'| equal
// to |shear|. The function is concave, so the projection is longest for a uniform slope,
// l sqrt(1 - (shear/l)^2), and shortest with all the depth change in one straight stretch,
// l - |shear|. (The rendered DER ribbon at 67 mm of shear on 200 mm: 153 mm, in [133, 189].)
void projected_length_bounds(double l, double shear, double *lo, double *hi)
{
    const double sr = std::min(1.0, std::fabs(shear) / l);
    *lo = l * (1.0 - sr);
    *hi = l * std::sqrt(1.0 - sr * sr);
}

// A cross-section centroid is the centreline only where the ribbon bends gently against its
// apparent width: where the radius of curvature comes within about twice the width of the ridge
// and the strip shows its face (twisted, in a tight fold, or the two legs of a closing loop
// merging into one wedge), the normal profile mixes in the neighbouring arc and the centroids
// slide to the outside of the bend (Delta Z off 1-6 px, A off 0.1-2 rad at quality 0.9-0.99 on the
// simulator family, every one at a ratio below 1.95). Seen edge on, the ridge's width is the
// blur's, and a tight bend costs nothing: the mock trial's lower state (320 x 240, creases at
// Gamma 0.13) sits at a ratio of 1.8-1.9 with a ridge 3 px wide, 2.5 px where narrowest, and is
// measured within target. So the ratio counts only where the face shows, the median ridge at
// least FACE_PX wider than the narrowest tenth of the ribbon (the edge-on stretches near the
// clamps); a curve tighter than its own ridge width (ratio below 1, a cusp) is refused either way.
// With min_bend_ratio (2 by default) such a frame is not measured.
const double FACE_PX = 2.0;

// Tightest radius of curvature of the smooth curve (mm, `ppmm` px per mm) over the valid samples'
// median ridge width, both in pixels; 1e9 (nothing to refuse) when the strip is seen edge on and
// the ratio is at least 1. (The widest ridge near the tightest point, tried instead, flags the
// creases of folded ribbons, which are tight but seen edge-on.)
double bend_over_width(const std::vector<Pt> &curve, double ppmm, const std::vector<vis::TraceSample> &smp,
                       std::vector<double> &w)
{
    w.clear();
    for (const auto &s : smp)
        if (s.valid)
            w.push_back(s.width);
    if (w.empty() || curve.size() < 3)
        return 1e9;
    std::nth_element(w.begin(), w.begin() + (long)(w.size() / 2), w.end());
    const double wmed = std::max(1.0, w[w.size() / 2]);
    std::nth_element(w.begin(), w.begin() + (long)(w.size() / 10), w.end());
    const double w10 = w[w.size() / 10];
    double rmin = 1e9;
    for (size_t j = 1; j + 1 < curve.size(); j++) {
        const Pt a = curve[j] - curve[j - 1], b = curve[j + 1] - curve[j];
        const double ang = std::fabs(std::atan2(a.x * b.y - a.y * b.x, a.dot(b)));
        if (ang > 0)
            rmin = std::min(rmin, 0.5 * (cv::norm(a) + cv::norm(b)) / ang * ppmm);
    }
    const double ratio = rmin / wmed;
    return ratio < 1.0 || wmed - w10 >= FACE_PX ? ratio : 1e9;
}

// The bend check's waiver for nearly mirror-symmetric shapes. Where the curve is tight, the smooth
// fit cuts the bend and the centroids slide off the centreline; what that does to A is mostly a
// shift of the arc-length midpoint (the two halves come out unequally short), times the tangent's
// turning rate there. On a nearly symmetric shape the two halves are cut alike and the midpoint
// stays: the symmetric snap's twisted U (ratios 1.28-1.98, |A| below 0.04) is measured with A
// within 0.035 rad on the simulator family and its sequences, while every shape at those ratios whose A
// came out 0.1 rad or more off had |A| of 0.14 or more (a loop's apex or an arch's flank at the
// midpoint). So between SYM_BEND_RATIO and min_bend_ratio a curve whose |A| is below SYM_A_RAD is
// measured. Delta Z there keeps the centroid's bias (0.67-0.71 px RMS, 1.11 px at most over the
// 187 such frames): right for the regime and the snap frame, not for the 0.3 px bar. Below
// SYM_BEND_RATIO (the Delta L 0.7 loop's merged legs, 1.14-1.24) it is refused whatever A.
const double SYM_BEND_RATIO = 1.25;
const double SYM_A_RAD = 0.1;

// A smooth curve that crosses background where the tracer found no ridge has bridged a gap it
// could not see (the followed U at 120 fps: the samples round its bottom missing, the fit's chord
// 5.6 px above the band, A within 0.03, quality 0.92). Every gap of invalid samples between two
// valid ones is checked: the curve points inside it must read at least the ridge level of the
// samples either side (their background + 30% of the lower peak, the tracer's own threshold).
// Returns the number of curve points off the ridge in the worst gap. With the bend check off, over
// the simulator family and its sequences (1473 attempts) it fired on 9: three were the frame's
// answer and 3.1-5.6 px wrong, the other six lost to a better attempt anyway.
int bridged_points(const cv::Mat &img, bool invert, const std::vector<Pt> &curve,
                   const std::vector<vis::TraceSample> &smp, double len_px)
{
    const size_t n = smp.size(), m = curve.size();
    int worst = 0;
    size_t k = 1;  // curve points before k lie before the current gap (gaps come in arc order)
    for (size_t i = 1; i < n;) {
        if (smp[i].valid || !smp[i - 1].valid) {
            i++;
            continue;
        }
        size_t j = i;
        while (j < n && !smp[j].valid)
            j++;
        if (j == n)
            break;  // no valid sample after the gap: the end margin, not a gap
        const vis::TraceSample &a = smp[i - 1], &b = smp[j];
        const double thr = 0.5 * (a.base + b.base) + 0.3 * std::min(a.peak, b.peak);
        const double fa = a.s / len_px, fb = b.s / len_px;
        int off = 0;
        while (k + 1 < m && (double)k / (double)(m - 1) <= fa)
            k++;
        for (; k + 1 < m && (double)k / (double)(m - 1) < fb; k++)
            if (vis::sample_at(img, invert, curve[k]) < thr)
                off++;
        worst = std::max(worst, off);
        i = j;
    }
    return worst;
}

// Occlusion: the ribbon is seen leaving both clamps (most samples valid in the first and last tenth)
// but a stretch longer than a fifth of the arc shows no ridge.
bool occluded(const std::vector<vis::TraceSample> &smp)
{
    const size_t n = smp.size();
    if (n < 20)
        return false;
    size_t run = 0, worst = 0, head = 0, tail = 0;
    for (size_t i = 0; i < n; i++) {
        run = smp[i].valid ? 0 : run + 1;
        worst = std::max(worst, run);
        if (i < n / 10)
            head += smp[i].valid;
        if (i >= n - n / 10)
            tail += smp[i].valid;
    }
    return worst > n / 5 && head * 3 >= (n / 10) * 2 && tail * 3 >= (n / 10) * 2;
}

void finish_attempt(vis_tracker *t, const Geometry &g, Attempt &at);

// Steps 5 to 7 from a guide curve, into `at`.
void track_from(vis_tracker *t, const Geometry &g, const std::vector<Pt> &guide_in, int passes,
                Attempt &at)
{
    at.ran = true;
    at.bends_modelled = false;
    at.followed = &at == &t->att[0];
    at.samples.clear();
    at.len_px = 0;
    at.reason = VIS_REASON_LOST;
    at.quality = 0;
    at.valid_frac = 0;
    at.length_rel = 0;
    at.bend_rel = 0;
    at.bend_refused = false;
    at.m = vis_measure{};
    const vis_track_params &p = t->p;
    vis::Workspace &ws = t->ws;
    std::vector<vis::TraceSample> &samples = ws.samples;
    std::vector<Pt> &guide = ws.guide;
    guide.assign(guide_in.begin(), guide_in.end());
    const double band_narrow = std::min(p.band_px, p.ribbon_max_px + 2.0);
    double len_px = 0;
    for (int pass = 0; pass < passes; pass++) {
        guide.front() = g.left;
        guide.back() = g.right;
        // Following, the first pass only refines the guide: every second sample is plenty there.
        const double step = pass + 1 < passes && passes == 2 ? 2.0 * p.step_px : p.step_px;
        vis::resample(guide, step, &len_px, ws.cum, ws.rs);
        if (len_px < 4 * p.end_margin_px + 8 || ws.rs.size() < 8) {
            at.reason = VIS_REASON_LOST;
            return;
        }
        vis::trace_pass(t->trace_img, t->trace_invert, ws.rs, pass == 0 ? p.band_px : band_narrow,
                        p.end_margin_px, p.min_contrast, p.ribbon_max_px, samples, ws.prof, ws.prof_tmp);
        size_t nv = 0;
        for (const auto &s : samples)
            nv += s.valid;
        if (samples.size() < 8 || nv < samples.size() / 2) {
            at.reason = occluded(samples) ? VIS_REASON_OCCLUDED : VIS_REASON_LOST;
            at.quality = samples.empty() ? 0 : (double)nv / samples.size();
            at.valid_frac = at.quality;
            return;
        }
        // Next guide: the clamp points and the valid samples, lightly smoothed.
        guide.clear();
        guide.push_back(g.left);
        for (const auto &s : samples)
            if (s.valid)
                guide.push_back(s.p);
        guide.push_back(g.right);
        if (pass + 1 < passes) {
            vis::smooth(guide, 2, ws.smooth_tmp);
            guide.swap(ws.smooth_tmp);
        }
    }
    at.len_px = len_px;
    vis::correct_section_bias(samples, ws.section);
    at.samples.assign(samples.begin(), samples.end());
    finish_attempt(t, g, at);
}

// Steps 6 and 7 from the attempt's samples (at.samples, at.len_px).
void finish_attempt(vis_tracker *t, const Geometry &g, Attempt &at)
{
    const vis_track_params &p = t->p;
    vis::Workspace &ws = t->ws;
    const std::vector<vis::TraceSample> &samples = at.samples;
    const double len_px = at.len_px;
    at.reason = VIS_REASON_LOST;
    at.quality = 0;
    at.length_rel = 0;
    at.bend_rel = 0;
    at.bend_refused = false;
    at.bridged = false;
    at.m = vis_measure{};
    size_t nv = 0;
    for (const auto &s : samples)
        nv += s.valid;
    if (samples.empty())
        return;
    const double valid_frac = (double)nv / samples.size();
    at.valid_frac = valid_frac;

    // Metric points: clamp, valid samples, clamp.
    std::vector<Pt> &px = ws.px, &und = ws.und;
    std::vector<double> &xi = ws.xi;
    px.clear();
    xi.clear();
    px.push_back(g.left);
    xi.push_back(0);
    for (const auto &s : samples)
        if (s.valid) {
            px.push_back(s.p);
            xi.push_back(s.s / len_px);
        }
    px.push_back(g.right);
    xi.push_back(1);
    at.traced_px.assign(px.begin(), px.end());
    und.assign(px.begin(), px.end());
    if (t->c.has_intrinsics) {
        cv::Mat K(3, 3, CV_64F, t->c.camera_matrix), dist(1, 5, CV_64F, t->c.dist);
        ws.ud_in.assign(px.begin() + 1, px.end() - 1);
        cv::undistortPoints(ws.ud_in, ws.ud_out, K, dist, cv::noArray(), K);
        std::copy(ws.ud_out.begin(), ws.ud_out.end(), und.begin() + 1);
    }
    vis::FitInput &fin = ws.fin;
    fin.xz.resize(und.size());
    fin.s.resize(und.size());
    // Depth depends on the arc fraction, which the image distorts (the far end looks shorter): a
    // first conversion uses the image's arc fraction, a second the metric curve's own.
    const int rounds = g.vm.D > 0 && g.shear != 0.0 ? 2 : 1;
    for (int round = 0; round < rounds; round++) {
        if (round > 0)
            for (size_t i = 0; i < und.size(); i++)
                xi[i] = fin.s[i] / fin.s.back();
        for (size_t i = 0; i < und.size(); i++) {
            fin.xz[i] = vis::view_to_metric(g.vm, und[i], depth_at(g, xi[i]));
            if (!std::isfinite(fin.xz[i].x) || !std::isfinite(fin.xz[i].y))
                return;  // LOST: a ray that misses the ribbon's plane
            fin.s[i] = i == 0 ? 0 : fin.s[i - 1] + cv::norm(fin.xz[i] - fin.xz[i - 1]);
        }
        if (!(fin.s.back() > 0))
            return;
    }
    for (size_t i = 1; i < fin.s.size(); i++)  // strictly increasing parameter
        if (!(fin.s[i] > fin.s[i - 1]))
            fin.s[i] = fin.s[i - 1] + 1e-9;
    vis::FitResult &fr = ws.fr;
    const int n_out = std::max(48, std::min(128, (int)(len_px / 20)));
    if (!vis::curve_fit(fin, p.fit_window * fin.s.back(), p.end_window * fin.s.back(), n_out, fr, ws.fit)) {
        // No smooth curve: a gap wider than the fit window (occlusion) or too few samples.
        at.reason = occluded(samples) ? VIS_REASON_OCCLUDED : VIS_REASON_LOST;
        return;
    }
    const double length = p.length_mm > 0 ? p.length_mm : fr.length;
    const double resid_px = fr.residual * g.vm.ppmm;
    at.quality = valid_frac / (1.0 + (resid_px / 0.5) * (resid_px / 0.5));
    at.bend_rel = bend_over_width(fr.curve, g.vm.ppmm, samples, ws.widths);
    const double bend_min = p.min_bend_ratio;
    const bool symmetric = at.bend_rel >= SYM_BEND_RATIO && std::fabs(fr.a) < SYM_A_RAD;
    at.bend_refused = at.bend_rel < bend_min && !symmetric && !at.bends_modelled;
    if (at.bend_refused)
        at.quality *= 0.1 * at.bend_rel / bend_min;
    at.m.dz = fr.height / length;
    at.m.a = fr.a;
    at.m.quality = at.quality;
    at.m.length_mm = fr.length;
    at.m.residual_px = resid_px;
    // Back to pixels for the midpoint and the curve.
    auto to_px = [&](Pt q, double x) { return vis::view_to_image(g.vm, q, depth_at(g, x)); };
    const Pt mid = to_px(fr.mid, 0.5);
    at.m.mid_px[0] = mid.x;
    at.m.mid_px[1] = mid.y;
    at.curve_px.resize(fr.curve.size());
    at.curve_mm.resize(fr.curve.size());
    for (size_t j = 0; j < fr.curve.size(); j++) {
        at.curve_px[j] = to_px(fr.curve[j], (double)j / (fr.curve.size() - 1));
        at.curve_mm[j] = fr.curve[j] - fin.xz[0];
    }
    if (t->c.has_intrinsics) {
        // The stored curve guides the next frame in raw image coordinates: redistort.
        cv::Mat K(3, 3, CV_64F, t->c.camera_matrix), dist(1, 5, CV_64F, t->c.dist);
        std::vector<cv::Point3d> &obj = t->obj3;
        obj.resize(at.curve_px.size());
        const double fx = t->c.camera_matrix[0], fy = t->c.camera_matrix[4];
        for (size_t j = 0; j < obj.size(); j++)
            obj[j] = cv::Point3d((at.curve_px[j].x - t->c.camera_matrix[2]) / fx,
                                 (at.curve_px[j].y - t->c.camera_matrix[5]) / fy, 1.0);
        cv::projectPoints(obj, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, dist, t->img2);
        at.curve_px.assign(t->img2.begin(), t->img2.end());
    }
    at.reason = VIS_REASON_NONE;
    for (const Pt &q : at.curve_px)
        if (!std::isfinite(q.x) || !std::isfinite(q.y)) {
            at.reason = VIS_REASON_LOST;  // a point the camera model cannot place
            return;
        }
    // Followed curves only (traced on the grey frame, read there too: by the time a followed
    // attempt is measured again from the silhouette model the tracer's image is the ridge
    // signal): a fresh path comes from the ridge itself, and there a jaw in front of the ribbon
    // reads as no ridge where the ribbon does pass behind it.
    if (at.followed && bridged_points(t->frame_grey, t->frame_dark, at.curve_px, samples, len_px) > 0) {
        at.bridged = true;
        at.reason = VIS_REASON_LOST;
        at.quality *= 0.1;
        at.m.quality = at.quality;
        return;
    }
    // A curve longer or shorter than the ribbon is not the ribbon: a shortcut across a loop or a
    // crossing, a path through clutter or along a clamp edge. With the length known, quality falls
    // with the mismatch (half at 4%) and beyond LENGTH_TOL the frame is not measured.
    at.length_rel = 0.0;
    if (p.length_mm > 0) {
        double lo, hi;
        projected_length_bounds(p.length_mm, g.shear, &lo, &hi);
        at.length_rel = fr.length < lo ? fr.length / lo - 1.0 : fr.length > hi ? fr.length / hi - 1.0 : 0.0;
        const double r = std::max(0.0, std::fabs(at.length_rel) - LENGTH_SLACK) / LENGTH_SLACK;
        at.quality /= 1.0 + r * r;
        at.m.quality = at.quality;
    }
    const bool bad_length = p.length_mm > 0 && std::fabs(at.length_rel) > LENGTH_TOL;
    if (bad_length || !std::isfinite(at.m.dz) || !std::isfinite(at.m.a))
        at.reason = VIS_REASON_LOST;
    else if (occluded(samples))
        at.reason = VIS_REASON_OCCLUDED;
    else if (at.quality < p.min_quality || at.bend_refused)
        at.reason = VIS_REASON_LOST;
}

// Tight bends with the face showing, measured by the silhouette model (bend_model.cpp) instead of
// being refused: `src` is an attempt the bend check refused; its samples through every stretch of
// the smooth curve tighter than min_bend_ratio ridge widths are replaced by the model's centreline
// (over the inner BEND_INNER of a window of BEND_WIDTHS median widths either side), and the
// attempt is measured again into `dst`, the bend check waived. False (dst not measured) when a
// bend's model does not explain the pixels: a residual on the band above BEND_RMS_NOISE times the
// image's noise (a coarse safeguard: over the family and its sequences the 31 accepted models
// reached 0.73-1.70 and all measured within 0.9 px and 0.07 rad; what keeps wrong answers out is
// the model's resolution, see bend_model.cpp), or a centreline moved by more than the band's
// half-width.
const double BEND_WIDTHS = 4.0;
const double BEND_RMS_NOISE = 2.0;
// The model tells the centreline from the band's inner edge, whose bulge at a twisted bend is
// about h_t^2 / 2R (a pixel or so): under a heavier blur it is washed out, and with noise 6 and
// blur 2 the crease corners came out up to 0.15 rad off at residuals at the noise. Not used there.
const double BEND_MAX_BLUR_PX = 1.5;

bool refine_bends(vis_tracker *t, const Geometry &g, const Attempt &src, Attempt &dst)
{
    dst.ran = false;
    dst.reason = VIS_REASON_LOST;
    const std::vector<Pt> &cm = src.curve_mm;
    const std::vector<vis::TraceSample> &smp = src.samples;
    if (cm.size() < 8 || smp.size() < 16 || !(src.len_px > 0))
        return false;
    std::vector<double> &w = t->ws.widths;
    w.clear();
    for (const auto &q : smp)
        if (q.valid)
            w.push_back(q.width);
    if (w.size() < 16)
        return false;
    std::nth_element(w.begin(), w.begin() + (long)(w.size() / 2), w.end());
    const double wmed = std::max(1.0, w[w.size() / 2]);
    const double rlim = t->p.min_bend_ratio * wmed;
    // Tight stretches of the smooth curve, measured as the bend check measures them (the metric
    // curve's radius in pixels at the calibration's scale), and their tightest points.
    const size_t m = cm.size();
    std::vector<double> cum(m, 0.0);
    for (size_t j = 1; j < m; j++)
        cum[j] = cum[j - 1] + cv::norm(cm[j] - cm[j - 1]);
    std::vector<double> centres;  // arc positions of the tightest points, as fractions of the arc
    double run_min = 1e18, run_at = -1;
    for (size_t j = 1; j + 1 <= m; j++) {
        double rad = 1e18;
        if (j + 1 < m) {
            const Pt a = cm[j] - cm[j - 1], b = cm[j + 1] - cm[j];
            const double ang = std::fabs(std::atan2(a.x * b.y - a.y * b.x, a.dot(b)));
            if (ang > 0)
                rad = 0.5 * (cv::norm(a) + cv::norm(b)) / ang * g.vm.ppmm;
        }
        if (rad < rlim) {
            if (rad < run_min) {
                run_min = rad;
                run_at = cum[j] / cum.back();
            }
        } else if (run_at >= 0) {
            centres.push_back(run_at);
            run_min = 1e18;
            run_at = -1;
        }
    }
    if (centres.empty())
        return false;
    dst.ran = true;
    dst.samples.assign(smp.begin(), smp.end());
    dst.len_px = src.len_px;
    dst.followed = src.followed;
    const double W = std::min(80.0, std::max(16.0, BEND_WIDTHS * wmed));
    for (double cf : centres) {
        const double sc = cf * src.len_px;
        if (sc - W < 0 || sc + W > src.len_px)
            return false;  // a bend at a clamp: the model needs arc on both sides
        std::vector<Pt> &win = t->bend_win, &oth = t->bend_others;
        win.clear();
        oth.clear();
        double sa = -1, sb = -1, hw = 0;
        for (const auto &q : dst.samples) {
            if (!q.valid)
                continue;
            if (q.s >= sc - W && q.s <= sc + W) {
                if (sa < 0)
                    sa = q.s;
                sb = q.s;
                win.push_back(q.p);
                hw = std::max(hw, 0.5 * q.width);
            } else if (q.s < sc - W - 3 || q.s > sc + W + 3) {
                oth.push_back(q.p);
            }
        }
        oth.push_back(g.left);
        oth.push_back(g.right);
        if (win.size() < 16 || !(sb > sa))
            return false;
        vis::BendFitInfo info;
        try {
            if (!t->bend_model.refine(t->frame_grey, t->frame_dark, win, oth, hw, BEND_RMS_NOISE, t->bend_out, &info))
                return false;
        } catch (const std::exception &) {
            return false;  // the model is an extra: its failure leaves the frame as refused
        }
        if (!(info.rms <= BEND_RMS_NOISE * info.noise) || !(info.sigma <= BEND_MAX_BLUR_PX) ||
            !(std::fabs(info.contrast) >= t->p.min_contrast) || !(info.delta_max <= std::max(1.0, hw)))
            return false;
        // The samples over the window's inner part take the model's centreline at their own arc
        // positions; their flags stay (a gap the tracer saw stays a gap).
        const std::vector<Pt> &out = t->bend_out;
        const double ia = sa + 0.5 * (1.0 - vis::BEND_INNER) * (sb - sa), ib = sb - 0.5 * (1.0 - vis::BEND_INNER) * (sb - sa);
        for (auto &q : dst.samples)
            if (q.valid && q.s >= ia && q.s <= ib) {
                const double k = (q.s - sa) / (sb - sa) * (double)(out.size() - 1);
                const size_t k0 = std::min(out.size() - 2, (size_t)std::max(0.0, std::floor(k)));
                const double f = std::min(1.0, std::max(0.0, k - (double)k0));
                const Pt np = out[k0] + f * (out[k0 + 1] - out[k0]);
                if (!std::isfinite(np.x) || !std::isfinite(np.y))
                    return false;
                q.p = np;
            }
    }
    dst.bends_modelled = true;
    finish_attempt(t, g, dst);
    return dst.reason == VIS_REASON_NONE;
}

// The better of two attempts: a measured one over one that is not; between two of the same kind,
// the higher quality (which already holds the length check and the residual).
// Between two measured ones of comparable quality (within 20%), the longer: a shortcut (across a
// loop, through a crossing, the wrong branch) is always shorter than the ribbon, and a longer path
// that is ridge all along (the quality says so) is ribbon.
Attempt *pick_better(Attempt *a, Attempt *b)
{
    if (!a)
        return b;
    const bool ma = a->reason == VIS_REASON_NONE, mb = b->reason == VIS_REASON_NONE;
    if (ma != mb)
        return ma ? a : b;
    if (ma) {
        const double la = a->m.length_mm, lb = b->m.length_mm;
        if (b->quality >= 0.8 * a->quality && lb > 1.02 * la)
            return b;
        if (a->quality >= 0.8 * b->quality && la > 1.02 * lb)
            return a;
    }
    return b->quality > a->quality ? b : a;
}

}  // namespace

extern "C" vis_status vis_tracker_process(vis_tracker *t, const vis_frame *f, double shear_mm,
                                          vis_measure *out, vis_error *err)
{
    if (!t || !out)
        return vis::fail(err, VIS_ERR_ARG, "vis_tracker_process: NULL tracker or output");
    if (!vis::finite(shear_mm))
        return vis::fail(err, VIS_ERR_ARG, "vis_tracker_process: shear_mm is not finite");
    measure_clear(out, VIS_REASON_UNREADABLE);
    // Every refresh_frames-th frame starts from scratch: a function of the count alone, so a
    // stretch that begins there tracks the same on a fresh copy of the tracker (track_pipe.cpp).
    if (t->p.refresh_frames > 0 && t->since_reset >= t->p.refresh_frames)
        vis_tracker_reset(t);
    t->since_reset++;
    if (!f || f->mat.empty() || f->mat.depth() != CV_8U) {
        vis::ok(err);
        return VIS_OK;
    }
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        const cv::Mat grey = vis::grey_of(f->mat);
        if (grey.size() != t->size) {
            t->size = grey.size();
            t->prev.clear();
        }
        const vis::Exposure ex = vis::exposure_check(grey, t->p.min_contrast);
        if (ex != vis::Exposure::ok) {
            measure_clear(out, ex == vis::Exposure::dark ? VIS_REASON_DARK : VIS_REASON_SATURATED);
            vis::ok(err);
            return VIS_OK;
        }
        if (vis::noise_check(grey, t->p.min_contrast)) {
            measure_clear(out, VIS_REASON_NOISE);
            vis::ok(err);
            return VIS_OK;
        }
        const vis_calib &c = t->c;
        Geometry g;
        if (c.has_intrinsics)
            g.vm.principal = Pt(c.camera_matrix[2], c.camera_matrix[5]);
        else if (c.principal_px[0] >= 0 && c.principal_px[1] >= 0)
            g.vm.principal = Pt(c.principal_px[0], c.principal_px[1]);
        else
            g.vm.principal = Pt(0.5 * (grey.cols - 1), 0.5 * (grey.rows - 1));
        g.vm.ppmm = c.px_per_mm;
        g.vm.D = c.camera_distance_mm;
        g.vm.tilt = c.camera_tilt_rad;
        g.shear = shear_mm;
        t->depth.prepare(t->p.length_mm, shear_mm);
        g.depth = &t->depth;
        if (g.vm.D > 0 && !(g.vm.D + shear_mm > 0.05 * g.vm.D))
            return vis::fail(err, VIS_ERR_ARG, "shear %g mm puts the clamp behind the camera", shear_mm);
        // The clamp points are calibrated at zero shear; the right one moves with the shear rail.
        g.left = Pt(c.clamp_left_px[0], c.clamp_left_px[1]);
        g.right = vis::view_to_image(
            g.vm, vis::view_to_metric(g.vm, Pt(c.clamp_right_px[0], c.clamp_right_px[1]), 0.0), shear_mm);
        auto inside = [&](Pt q) {
            return std::isfinite(q.x) && std::isfinite(q.y) && q.x >= 0 && q.y >= 0 && q.x <= grey.cols - 1 && q.y <= grey.rows - 1;
        };
        if (!inside(g.left) || !inside(g.right)) {
            measure_clear(out, VIS_REASON_CLAMP_NOT_FOUND);
            vis::ok(err);
            return VIS_OK;
        }
        const bool dark = t->polarity ? t->polarity == 1 : vis::polarity_is_dark(grey);
        t->frame_grey = grey;
        t->frame_dark = dark;
        const int r = (int)std::ceil(t->p.ribbon_max_px);
        const cv::Rect full(0, 0, grey.cols, grey.rows);
        Attempt *best = nullptr;
        for (Attempt &a : t->att)
            a.ran = false;
        if (!t->prev.empty()) {
            // Following: trace the grey levels themselves (each profile has its own background).
            t->trace_img = grey;
            t->trace_invert = dark;
            track_from(t, g, t->prev, 2, t->att[0]);  // the previous curve is close: two passes
            best = &t->att[0];
        }
        bool any_path = best != nullptr;
        // A followed curve whose length changed from the last frame's may have slid onto a
        // shortcut (a loop forming below a crossing): look from scratch as well.
        const bool length_jump = best && best->reason == VIS_REASON_NONE && t->prev_length > 0 &&
                                 std::fabs(best->m.length_mm / t->prev_length - 1.0) > 0.02;
        if (!best || best->reason != VIS_REASON_NONE || length_jump) {
            // Fresh acquisition: the ridge signal of the whole frame, then candidate paths (walks
            // from either clamp, the geodesic), each refined and measured; the best measured one
            // wins (see pick_better). The previous curve never limits where the ribbon can be.
            vis::ridge_signal(grey, dark, r, full, t->work, t->sig);
            t->trace_img = t->sig;
            t->trace_invert = false;
            const double sref = vis::signal_reference(t->sig);
            vis::WalkParams wp;
            wp.step = 2.0;
            wp.half_band = 0.5 * t->p.ribbon_max_px + 2.0;
            wp.threshold = std::max(0.5 * t->p.min_contrast, 0.25 * sref);
            const double len_px = t->p.length_mm > 0 ? t->p.length_mm * g.vm.ppmm : 0.0;
            wp.max_len = len_px > 0 ? 1.6 * len_px : 3.0 * (grey.cols + grey.rows);
            wp.max_gap = std::max(12.0, len_px > 0 ? 0.06 * len_px : 0.03 * (grey.cols + grey.rows));
            wp.arrive = 2.0 * wp.step + 1.0;
            bool walked = false;
            for (int dir = 0; dir < 2 && sref > 0; dir++) {
                const bool okw = dir == 0 ? vis::path_walk(t->sig, g.left, g.right, wp, t->path)
                                          : vis::path_walk(t->sig, g.right, g.left, wp, t->path);
                if (!okw)
                    continue;
                if (dir == 1)
                    std::reverse(t->path.begin(), t->path.end());
                any_path = true;
                vis::smooth(t->path, 2, t->ws.smooth_tmp);
                Attempt &w = t->att[1 + dir];
                track_from(t, g, t->ws.smooth_tmp, 3, w);
                best = pick_better(best, &w);
                walked = walked || w.reason == VIS_REASON_NONE;
            }
            if (!walked && vis::path_init(t->sig, sref, g.left, g.right, t->path)) {
                any_path = true;
                vis::smooth(t->path, 3, t->ws.smooth_tmp);
                Attempt &fresh = t->att[3];
                track_from(t, g, t->ws.smooth_tmp, 3, fresh);
                best = pick_better(best, &fresh);
            }
        }
        // The bend is the ribbon's, not the path's: a followed curve that passes the bend check
        // while a fresh path of the same length, ridge all along, is refused by it has cut the
        // tight bend short (the symmetric snap's U at 500 fps: the followed curve's tightest radius
        // 14 px against the walks' 10 px, A off 0.13 rad at quality 0.92, the walks within 0.01
        // rad). Such a frame is lost, not measured.
        if (best == &t->att[0] && best->reason == VIS_REASON_NONE && t->p.min_bend_ratio > 0)
            for (int i = 1; i < 4; i++) {
                const Attempt &a = t->att[i];
                if (a.ran && a.reason == VIS_REASON_LOST && a.bend_rel >= 1.0 && a.bend_refused &&
                    a.valid_frac >= 0.95 && std::fabs(a.m.length_mm / best->m.length_mm - 1.0) < 0.05) {
                    best->reason = VIS_REASON_LOST;
                    best->quality = std::min(best->quality, a.quality);
                    break;
                }
            }
        // No attempt measured, and one was refused only for a tight bend with the face showing:
        // measure its bends with the silhouette model (refine_bends). Of such attempts, the one
        // with the most ridge along it and the length nearest the ribbon's.
        t->bent.ran = false;
        if (best && best->reason != VIS_REASON_NONE && t->p.min_bend_ratio > 0) {
            const Attempt *cand = nullptr;
            for (const Attempt &a : t->att)
                if (a.ran && a.bend_refused && !a.bridged && a.valid_frac >= 0.9 && std::fabs(a.length_rel) <= LENGTH_TOL &&
                    (!cand || a.valid_frac - std::fabs(a.length_rel) > cand->valid_frac - std::fabs(cand->length_rel)))
                    cand = &a;
            if (cand && refine_bends(t, g, *cand, t->bent))
                best = pick_better(best, &t->bent);
        }
        // With a prediction's shapes: measure again with the depth of the one nearest to what was
        // measured, by its projection when the library has them, else by Delta Z and A (the
        // pixels are traced again along the curve just found).
        if (best && best->reason == VIS_REASON_NONE && !t->library.empty()) {
            const long k = t->library.has_curves() ? t->library.nearest_curve(shear_mm, best->curve_mm)
                                                   : t->library.nearest(shear_mm, best->m.dz, best->m.a);
            if (t->library.use(k, t->depth)) {
                t->depth.prepare(t->p.length_mm, shear_mm);
                if (best == &t->bent) {
                    // The model's centreline is in pixels: measured again at the new depth as it
                    // is (traced again, the centroids would slide back into the bend).
                    t->redo = t->bent;
                    finish_attempt(t, g, t->redo);
                } else {
                    track_from(t, g, best->curve_px, 2, t->redo);  // redo is never best here
                }
                if (t->redo.reason == VIS_REASON_NONE)
                    best = &t->redo;
            }
        }
        if (best && best->reason == VIS_REASON_LOST && best->valid_frac < 0.25)
            any_path = false;  // nothing ribbon-like along any path
        if (!best || !any_path) {
            measure_clear(out, VIS_REASON_NO_RIBBON);
            t->curve.clear();
    t->traced.clear();
            vis::ok(err);
            return VIS_OK;
        }
        if (best->reason == VIS_REASON_NONE) {
            *out = best->m;
            out->reason = VIS_REASON_NONE;
            t->prev = best->curve_px;
            t->prev_length = best->m.length_mm;
            t->curve = best->curve_px;
            t->traced = best->traced_px;
            if (t->polarity == 0)
                t->polarity = dark ? 1 : 2;  // keep the polarity once the ribbon is found
        } else {
            measure_clear(out, best->reason);
            out->quality = best->quality;
            t->curve.clear();
    t->traced.clear();
        }
        vis::ok(err);
        return VIS_OK;
    })
}
