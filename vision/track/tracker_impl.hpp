// tracker_impl.hpp: private stages of the tracker (one file each), in pipeline order:
//   signal.cpp     frame -> ridge signal image (background removed, polarity folded in)
//   path_init.cpp  ridge signal -> a first pixel path between the clamps (no previous curve)
//   path_walk.cpp  ridge signal -> the same by walking the ridge (loops, crossings)
//   trace.cpp      image + guide curve -> sub-pixel centreline samples along the arc
//   view_model.cpp pixels <-> millimetres in the ribbon's plane (depth from the shear, camera pitch)
//   depth_profile.cpp the centreline's depth along the arc (default cubic, or a prediction's)
//   section_bias.cpp samples -> the same, moved onto the centreline where the sections are oblique
//   curve_fit.cpp  samples -> smooth metric curve -> Delta Z, A, midpoint
//   bend_model.cpp image + samples through a tight twisted bend -> the centreline there, from a
//                  model of the band's silhouette
#ifndef RIBBON_VIS_TRACKER_IMPL_HPP
#define RIBBON_VIS_TRACKER_IMPL_HPP

#include "vis_internal.hpp"
#include "vis_track.h"

#include <memory>
#include <string>
#include <vector>

namespace vis {

using Pt = cv::Point2d;

// --- signal.cpp
enum class Exposure { ok, dark, saturated };
// Global exposure check on an 8-bit grey frame.
Exposure exposure_check(const cv::Mat &grey, double min_contrast);
// True when the frame is noise: neighbouring pixels as different as any two (no structure) and
// the spread well above the weakest contrast followed.
bool noise_check(const cv::Mat &grey, double min_contrast);
// Decide the polarity from the histogram: true when the ribbon is darker than the background.
bool polarity_is_dark(const cv::Mat &grey);
// Ridge signal in `roi` of `grey` (black-hat or top-hat with a square of side 2 r + 1), CV_32F.
void ridge_signal(const cv::Mat &grey, bool dark, int r, cv::Rect roi, cv::Mat &work, cv::Mat &sig);


// --- path_init.cpp
// Cheapest 8-connected path from a to b where a step costs length / (eps + S / s_ref), s_ref the
// signal's reference level (signal_reference). Pixels of the full image (sig covers it); coarse to
// fine on large frames. Returns false when either end is outside or no path exists.
bool path_init(const cv::Mat &sig, double s_ref, Pt a, Pt b, std::vector<Pt> &path);
// The 99.5th percentile of the positive signal (every second pixel of every second row), 0 if none.
double signal_reference(const cv::Mat &sig);

// --- path_walk.cpp
struct WalkParams {
    double step;       // px between walk points (2)
    double half_band;  // px either side of the predicted point searched for the ridge
    double threshold;  // weakest ridge signal followed
    double max_gap;    // px of arc bridged without a ridge
    double max_len;    // px: longer walks fail
    double arrive;     // px: within this of the other clamp point the walk is done
};
// Walk the ridge of `sig` from clamp point a to clamp point b (see path_walk.cpp). False when the
// walk does not arrive.
bool path_walk(const cv::Mat &sig, Pt a, Pt b, const WalkParams &wp, std::vector<Pt> &path);

// --- trace.cpp
struct TraceSample {
    Pt p;          // sub-pixel centre, pixels (image coordinates)
    double s;      // arc position along the guide, pixels from the left clamp
    double peak;   // ridge height above the profile's lower quartile, grey levels
    bool valid;    // a clear ridge was found
    double width;  // px, the ridge's extent above 30% of its height (valid samples)
    double base;   // the profile's lower quartile (the local background), grey levels
};
// Bilinear sample of `img` (CV_8U or CV_32F, inverted when `invert`) at q, 0 outside.
float sample_at(const cv::Mat &img, bool invert, Pt q);
// Resample `guide` (from left clamp to right clamp) every `step` px into `out`; polyline length in
// *len; `cum` is scratch.
void resample(const std::vector<Pt> &guide, double step, double *len, std::vector<double> &cum,
              std::vector<Pt> &out);
// Moving-average smoothing with half-width h samples into `out` (not `c`), ends kept fixed.
void smooth(const std::vector<Pt> &c, int h, std::vector<Pt> &out);
// One pass of the tracer on `img` (the CV_32F ridge signal, or the CV_8U grey frame, inverted when
// `invert`): profiles along the normals of `guide` (already resampled), centroid of the ridge within
// +-band px, skipping samples within `margin` px of either end.
void trace_pass(const cv::Mat &img, bool invert, const std::vector<Pt> &guide, double band,
                double margin, double min_contrast, double max_width, std::vector<TraceSample> &out,
                std::vector<float> &prof, std::vector<float> &tmp);

// --- section_bias.cpp
struct SectionScratch {
    std::vector<size_t> idx;
    std::vector<double> hw, tmp, th, s, shift;
    std::vector<Pt> nrm;
};
// Moves the valid samples in bends back onto the centreline where the band's cross-sections are
// oblique to the curve (the centroid's bias there, from the samples' own widths; see
// section_bias.cpp).
void correct_section_bias(std::vector<TraceSample> &smp, SectionScratch &ws);

// --- bend_model.cpp
// The part of a bend's window (its middle, as a fraction of it) whose centreline the model gives
// the tracer: the window's ends are held only by the pixels on one side.
constexpr double BEND_INNER = 0.6;
struct BendFitInfo {
    double rms = 0;        // residual RMS over the band's pixels, grey levels
    double noise = 0;      // the image's noise, read away from the ribbon, grey levels
    double contrast = 0;   // the silhouette's contrast above the background, grey levels
    double sigma = 0;      // blur, px
    double delta_max = 0;  // largest move of the centreline over the window's inner part, px
};
// The centreline through a tight bend from a model of the band's silhouette (see bend_model.cpp).
class BendModel {
public:
    BendModel();
    ~BendModel();
    // Only scratch inside: a copy starts with its own, empty.
    BendModel(const BendModel &);
    BendModel &operator=(const BendModel &);
    // `window`: the traced centreline over the bend (pixels, in arc order); `others`: points of the
    // rest of the ribbon (pixels whose nearest point is one of these are not counted);
    // `half_width_px`: the band's largest half-width there. `img` as for trace_pass (CV_8U grey
    // or CV_32F ridge signal, `invert` for a dark ribbon on grey). On success `out` holds the
    // model's centreline, every 1 px along the window. A model whose residual over the band is
    // above max_rms_over_noise times the background's noise is fitted again broken at the middle
    // (a crease); the caller judges the result by info.
    bool refine(const cv::Mat &img, bool invert, const std::vector<Pt> &window, const std::vector<Pt> &others,
                double half_width_px, double max_rms_over_noise, std::vector<Pt> &out, BendFitInfo *info);

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// --- view_model.cpp
struct ViewModel {
    Pt principal;  // principal point, pixels
    double ppmm;   // pixels per mm at the distance D along the optical axis
    double D;      // mm from the camera centre to where the optical axis meets y = 0; 0 = unknown
    double tilt;   // pitch, radians, positive looks down (as vis_camera.tilt_rad)
};
// Pixel (undistorted) on the surface y = depth (mm, away from the camera) -> (x, z) mm relative to
// the optical axis' point on y = 0; NaN when the ray misses.
Pt view_to_metric(const ViewModel &m, Pt uv, double depth);
// The inverse: (x, z) mm at depth -> pixel; NaN when behind the camera.
Pt view_to_image(const ViewModel &m, Pt xz, double depth);

// --- depth_profile.cpp
// Depth over the shear along the projected arc: the default cubic 3 xi^2 - 2 xi^3, or a caller's
// profile (material arc fraction -> depth / shear) mapped per frame onto the projected arc.
class DepthProfile {
public:
    static constexpr size_t MAX_POINTS = 100000;
    static constexpr double MAX_REL = VIS_DEPTH_REL_MAX;
    // n = 0 restores the cubic; false (with why) for a profile that is not one.
    bool set(const double *frac, const double *rel, size_t n, std::string &why);
    // Map onto the projected arc for a ribbon of length_mm (0 = unknown) at this shear.
    void prepare(double length_mm, double shear_mm);
    // Depth / shear at projected arc fraction xi (clamped to [0, 1]).
    double at(double xi) const;
    bool custom() const { return !frac_.empty(); }
    // A profile already checked (a library's shape): copied into the buffers kept, no allocation
    // once they have the size.
    void set_checked(const double *frac, const double *rel, size_t n);

private:
    std::vector<double> frac_, rel_, proj_;
};

// Shapes a prediction expects (vis_tracker_set_depth_library), each keyed by its shear, Delta Z and
// A: a frame measured as (shear, Delta Z, A) takes the depth of the nearest one, distances in
// units of KEY_SHEAR_MM, KEY_DZ and KEY_A_RAD.
class DepthLibrary {
public:
    static constexpr size_t MAX_SHAPES = 200000, MAX_POINTS = 4096, MAX_VALUES = 50000000;
    static constexpr double KEY_SHEAR_MM = 2.0, KEY_DZ = 0.005, KEY_A_RAD = 0.02;
    bool set(const vis_depth_library *lib, std::string &why);  // NULL or no shapes: none
    bool empty() const { return shear_.empty(); }
    // The nearest shape by shear, Delta Z and A (-1 when empty).
    long nearest(double shear_mm, double dz, double a) const;
    // With projections: the shape whose projection (KEY_POINTS points evenly along its arc) is
    // nearest to `curve` (mm, relative to the left clamp, from left clamp to right), RMS distance
    // in units of KEY_XZ_MM, shear as above; -1 without projections.
    long nearest_curve(double shear_mm, const std::vector<Pt> &curve) const;
    bool has_curves() const { return !key_xz_.empty(); }
    static constexpr int KEY_POINTS = 16;
    static constexpr double KEY_XZ_MM = 0.5;
    bool use(long i, DepthProfile &into) const;                 // shape i's profile into `into`

private:
    std::vector<double> shear_, dz_, a_, frac_, rel_;
    std::vector<Pt> key_xz_;  // n_shapes x KEY_POINTS
    mutable std::vector<Pt> probe_;
    static void resample_even(const std::vector<Pt> &c, Pt *out);  // KEY_POINTS points
    size_t n_points_ = 0;
};

// --- curve_fit.cpp
struct FitInput {
    std::vector<Pt> xz;      // metric points (mm), z up, from left clamp to right clamp
    std::vector<double> s;   // their chord-length parameter, mm
};
struct FitResult {
    double length;           // arc length of the smooth curve, mm
    double height;           // midpoint height above the clamp chord, mm (positive = left of chord)
    double a;                // 2 theta(1/2) - theta(0) - theta(1), radians
    Pt mid;                  // midpoint, mm
    double residual;         // median distance of the points from the fit, mm
    std::vector<Pt> curve;   // smooth curve samples, mm
};
struct FitScratch {
    std::vector<double> cum, speed, res;
};
// Local polynomial regression: half-window `hw` (mm) around interior points; the end tangents from
// one-sided windows of length `he` (mm).
bool curve_fit(const FitInput &in, double hw, double he, int n_out, FitResult &out, FitScratch &ws);

// Every buffer a frame needs, kept by the tracker so that, once sizes settle, tracking a frame
// allocates nothing (the geodesic search of a fresh acquisition excepted).
struct Workspace {
    std::vector<Pt> guide, rs, smooth_tmp, px, und;
    std::vector<double> cum, xi, widths;
    std::vector<TraceSample> samples;
    std::vector<float> prof, prof_tmp;
    std::vector<cv::Point2d> ud_in, ud_out;
    FitInput fin;
    FitResult fr;
    FitScratch fit;
    SectionScratch section;
};

// --- tracker.cpp, for track_pipe.cpp
// A copy of t (its parameters, calibration, depth profile and library) in the state
// vis_tracker_reset leaves, with scratch of its own.
vis_tracker *tracker_fresh_copy(const vis_tracker *t);
// What carries from one frame to the next (previous curve, polarity, depth, the refresh count),
// copied from `from` into `into`.
void tracker_take_state(vis_tracker *into, const vis_tracker *from);
// Let go of the frame's pixels (views kept for the tracer), so the caller may reuse the buffer.
void tracker_drop_views(vis_tracker *t);
int tracker_refresh_frames(const vis_tracker *t);
// An owned tracker (freed with vis_tracker_free).
struct TrackerFree {
    void operator()(vis_tracker *t) const { vis_tracker_free(t); }
};
using TrackerPtr = std::unique_ptr<vis_tracker, TrackerFree>;
long tracker_since_reset(const vis_tracker *t);  // vis_tracker_process calls since made or reset

}  // namespace vis

#endif
