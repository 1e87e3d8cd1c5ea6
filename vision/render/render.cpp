// render.cpp: the synthetic renderer: a simulated ribbon seen from the side through a pinhole.
//
// The ribbon is drawn as the solid it is: at every centreline point a width x thickness rectangle
// (across the width direction d = t x n and the normal n), and between two neighbouring points the
// convex hull of the two rectangles' eight projected corners. The union of those hulls is the
// ribbon's silhouette, with perspective (the near edge looks bigger than the far one) and twist (a
// tilted normal shows the face). Clamp jaws are boxes continuing the ribbon outward from each clamp
// point. Rasterisation is exact point-in-polygon at `supersample`^2 samples per pixel, then a box
// average; sample (X, Y) of the fine grid maps to pixel coordinate ((X + 0.5)/k - 0.5, ...), so the
// averaged image keeps OpenCV's pixel-centre convention and the tracker's sub-pixel results can be
// compared with projected ground truth without a half-pixel offset.
// Then, in order: clutter (behind everything), illumination (gradient and vignette), optical blur,
// Gaussian noise, rounding to 8 bits. The random generator lives in the renderer and is seeded from
// the parameters, so a sequence is reproducible.
#include "vis_internal.hpp"

#include "camera_model.hpp"
#include "shape_truth.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <vector>

struct vis_renderer {
    vis_render_params p;
    cv::RNG rng;
    cv::Mat fine;     // CV_32F, supersampled canvas
    cv::Mat coarse;   // CV_32F, image size
    cv::Mat noise;    // CV_32F
    cv::Mat gain;     // CV_32F illumination
};

namespace {

// Fill the convex hull of `pts` (fine-grid coordinates) with `value` into `img` (CV_32F).
void fill_hull(cv::Mat &img, const std::vector<cv::Point2f> &pts, float value)
{
    std::vector<cv::Point2f> hull;
    cv::convexHull(pts, hull);
    const size_t m = hull.size();
    if (m < 3)
        return;
    float x0 = hull[0].x, x1 = x0, y0 = hull[0].y, y1 = y0;
    for (const auto &q : hull) {
        x0 = std::min(x0, q.x); x1 = std::max(x1, q.x);
        y0 = std::min(y0, q.y); y1 = std::max(y1, q.y);
    }
    if (!(x1 >= 0 && y1 >= 0 && x0 <= img.cols - 1 && y0 <= img.rows - 1))
        return;  // off the image (also keeps huge coordinates away from the int conversions)
    x0 = std::max(x0, -1.f);
    y0 = std::max(y0, -1.f);
    x1 = std::min(x1, (float)img.cols);
    y1 = std::min(y1, (float)img.rows);
    const int X0 = std::max(0, (int)std::ceil(x0)), X1 = std::min(img.cols - 1, (int)std::floor(x1));
    const int Y0 = std::max(0, (int)std::ceil(y0)), Y1 = std::min(img.rows - 1, (int)std::floor(y1));
    // Orientation of the hull, so the inside test works for either winding.
    double area = 0;
    for (size_t i = 0; i < m; i++) {
        const auto &a = hull[i], &b = hull[(i + 1) % m];
        area += (double)a.x * b.y - (double)b.x * a.y;
    }
    const double sgn = area >= 0 ? 1.0 : -1.0;
    for (int Y = Y0; Y <= Y1; Y++) {
        float *row = img.ptr<float>(Y);
        for (int X = X0; X <= X1; X++) {
            bool in = true;
            for (size_t i = 0; i < m && in; i++) {
                const auto &a = hull[i], &b = hull[(i + 1) % m];
                const double c = ((double)b.x - a.x) * (Y - a.y) - ((double)b.y - a.y) * (X - a.x);
                in = sgn * c >= -1e-9;
            }
            if (in)
                row[X] = value;
        }
    }
}

struct V3 {
    double x, y, z;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 unit(V3 a)
{
    const double l = std::sqrt(dot(a, a));
    return l > 0 ? (1.0 / l) * a : a;
}

}  // namespace

extern "C" vis_render_params vis_render_params_default(void)
{
    vis_render_params p;
    p.camera = vis_camera_default();
    p.background = 200.0;
    p.ribbon = 40.0;
    p.clamp = 90.0;
    p.clamp_length_m = 0.015;
    p.clamp_height_m = 0.012;
    p.noise_sigma = 2.0;
    p.blur_sigma_px = 0.8;
    p.light_gradient = 0.0;
    p.vignette = 0.0;
    p.clutter = 0;
    p.supersample = 4;
    p.seed = 1;
    return p;
}

static bool render_params_valid(const vis_render_params *p, vis_error *err)
{
    if (!vis::camera_valid(p->camera, err))
        return false;
    const double lv[3] = {p->background, p->ribbon, p->clamp};
    for (double v : lv)
        if (!vis::finite(v) || v < 0 || v > 255) {
            vis::fail(err, VIS_ERR_ARG, "render: grey levels must be in 0..255");
            return false;
        }
    if (!vis::finite(p->clamp_length_m) || p->clamp_length_m < 0 || !vis::finite(p->clamp_height_m) ||
        p->clamp_height_m < 0 || !vis::finite(p->noise_sigma) || p->noise_sigma < 0 ||
        p->noise_sigma > 100 || !vis::finite(p->blur_sigma_px) || p->blur_sigma_px < 0 ||
        p->blur_sigma_px > 50 || !vis::finite(p->light_gradient) || std::fabs(p->light_gradient) > 1 ||
        !vis::finite(p->vignette) || p->vignette < 0 || p->vignette > 1 || p->clutter < 0 ||
        p->clutter > 1000 || p->supersample < 1 || p->supersample > 8) {
        vis::fail(err, VIS_ERR_ARG,
                  "render: need clamp sizes >= 0, 0 <= noise_sigma <= 100, 0 <= blur_sigma_px <= 50, "
                  "|light_gradient| <= 1, 0 <= vignette <= 1, 0 <= clutter <= 1000, "
                  "1 <= supersample <= 8");
        return false;
    }
    return true;
}

extern "C" vis_renderer *vis_renderer_create(const vis_render_params *p, vis_error *err)
{
    if (!p) {
        vis::fail(err, VIS_ERR_ARG, "vis_renderer_create: NULL params");
        return nullptr;
    }
    if (!render_params_valid(p, err))
        return nullptr;
    VIS_GUARD(err, nullptr, {
        vis_renderer *r = new vis_renderer;
        r->p = *p;
        r->rng = cv::RNG(p->seed ? p->seed : 1);
        const int k = p->supersample, W = p->camera.width_px, H = p->camera.height_px;
        r->fine.create(H * k, W * k, CV_32F);
        r->coarse.create(H, W, CV_32F);
        r->noise.create(H, W, CV_32F);
        r->gain.create(H, W, CV_32F);
        const double cu = 0.5 * (W - 1), cv_ = 0.5 * (H - 1), rc2 = cu * cu + cv_ * cv_;
        for (int v = 0; v < H; v++)
            for (int u = 0; u < W; u++) {
                const double r2 = ((u - cu) * (u - cu) + (v - cv_) * (v - cv_)) / rc2;
                r->gain.at<float>(v, u) =
                    (float)((1.0 + p->light_gradient * (u - cu) / W) * (1.0 - p->vignette * r2));
            }
        vis::ok(err);
        return r;
    })
}

extern "C" void vis_renderer_free(vis_renderer *r) { delete r; }

extern "C" vis_status vis_renderer_draw(vis_renderer *r, const vis_shape *shape, vis_frame *out,
                                        vis_render_truth *truth, vis_error *err)
{
    if (!r || !out)
        return vis::fail(err, VIS_ERR_ARG, "vis_renderer_draw: NULL renderer or frame");
    if (!vis::shape_valid(shape, err))
        return VIS_ERR_ARG;
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        const vis_render_params &p = r->p;
        const vis_camera &cam = p.camera;
        const int k = p.supersample;
        const size_t n = shape->n;
        auto P = [&](size_t i) {
            return V3{shape->pos[3 * i], shape->pos[3 * i + 1], shape->pos[3 * i + 2]};
        };
        auto N = [&](size_t i) {
            return V3{shape->normal[3 * i], shape->normal[3 * i + 1], shape->normal[3 * i + 2]};
        };
        auto tangent = [&](size_t i) {
            const size_t a = i == 0 ? 0 : i - 1, b = i == n - 1 ? n - 1 : i + 1;
            return unit(P(b) - P(a));
        };
        // Project a world point to the fine grid; false if behind the camera.
        auto proj = [&](V3 q, cv::Point2f &o) {
            const double w[3] = {q.x, q.y, q.z};
            double uv[2];
            if (!vis::camera_project(cam, w, uv))
                return false;
            o.x = (float)((uv[0] + 0.5) * k - 0.5);
            o.y = (float)((uv[1] + 0.5) * k - 0.5);
            return true;
        };
        auto section = [&](V3 c, V3 t, V3 nn, double half_w, double half_b,
                           std::vector<cv::Point2f> &pts) {
            nn = unit(nn - dot(nn, t) * t);
            const V3 d = unit(cross(t, nn));
            for (int a = -1; a <= 1; a += 2)
                for (int b = -1; b <= 1; b += 2) {
                    cv::Point2f o;
                    if (!proj(c + (a * half_w) * d + (b * half_b) * nn, o))
                        return false;
                    pts.push_back(o);
                }
            return true;
        };

        // Backdrop and clutter. The clutter has its own generator, re-seeded every frame, so it
        // stays put from frame to frame like a real background (the noise does not).
        r->fine.setTo(cv::Scalar(p.background));
        cv::RNG crng(p.seed * 2654435761u + 12345u);
        for (int c = 0; c < p.clutter; c++) {
            const float W = (float)r->fine.cols, H = (float)r->fine.rows;
            const cv::Point2f ctr(crng.uniform(0.f, W), crng.uniform(0.f, H));
            const cv::Size2f sz(crng.uniform(0.08f, 0.3f) * W, crng.uniform(0.08f, 0.3f) * H);
            const float ang = crng.uniform(0.f, 180.f);
            const double level = p.background + crng.uniform(-0.35, 0.35) *
                                                    std::fabs(p.background - p.ribbon);
            if (c % 2 == 0)
                cv::ellipse(r->fine, cv::RotatedRect(ctr, sz, ang), cv::Scalar(level), cv::FILLED);
            else {
                cv::Point2f v[4];
                cv::RotatedRect(ctr, sz, ang).points(v);
                std::vector<cv::Point> iv(v, v + 4);
                cv::fillConvexPoly(r->fine, iv, cv::Scalar(level));
            }
        }
        // Clamp jaws: boxes from each clamp point outward along the end tangent.
        const double hw = 0.5 * shape->width_m, hb = 0.5 * shape->thickness_m;
        if (p.clamp_length_m > 0 && p.clamp_height_m > 0) {
            for (int end = 0; end < 2; end++) {
                const size_t i = end == 0 ? 0 : n - 1;
                const V3 t = tangent(i);
                const V3 out_dir = end == 0 ? -1.0 * t : t;
                std::vector<cv::Point2f> pts;
                bool okp = section(P(i), t, N(i), std::max(hw, 1e-4), 0.5 * p.clamp_height_m, pts) &&
                           section(P(i) + p.clamp_length_m * out_dir, t, N(i), std::max(hw, 1e-4),
                                   0.5 * p.clamp_height_m, pts);
                if (okp)
                    fill_hull(r->fine, pts, (float)p.clamp);
            }
        }
        // The ribbon, segment by segment.
        std::vector<cv::Point2f> pts;
        pts.reserve(8);
        for (size_t i = 0; i + 1 < n; i++) {
            pts.clear();
            if (!section(P(i), tangent(i), N(i), hw, hb, pts) ||
                !section(P(i + 1), tangent(i + 1), N(i + 1), hw, hb, pts))
                return vis::fail(err, VIS_ERR_ARG, "render: ribbon point %zu is behind the camera", i);
            fill_hull(r->fine, pts, (float)p.ribbon);
        }
        // Down to the image, then light, blur and noise.
        cv::resize(r->fine, r->coarse, r->coarse.size(), 0, 0, cv::INTER_AREA);
        cv::multiply(r->coarse, r->gain, r->coarse);
        if (p.blur_sigma_px > 0)
            cv::GaussianBlur(r->coarse, r->coarse, cv::Size(0, 0), p.blur_sigma_px, p.blur_sigma_px,
                             cv::BORDER_REFLECT);
        if (p.noise_sigma > 0) {
            r->rng.fill(r->noise, cv::RNG::NORMAL, 0.0, p.noise_sigma);
            r->coarse += r->noise;
        }
        r->coarse.convertTo(out->mat, CV_8U);  // rounds and saturates to 0..255

        if (truth) {
            vis::ShapeTruth st = vis::shape_truth(*shape);
            truth->truth = st.truth;
            double uv[2];
            vis::camera_project(cam, shape->pos, uv);
            truth->clamp_left_px[0] = uv[0];
            truth->clamp_left_px[1] = uv[1];
            vis::camera_project(cam, shape->pos + 3 * (n - 1), uv);
            truth->clamp_right_px[0] = uv[0];
            truth->clamp_right_px[1] = uv[1];
            vis::camera_project(cam, st.mid3, uv);
            truth->mid_px[0] = uv[0];
            truth->mid_px[1] = uv[1];
            truth->px_per_m = cam.focal_px / cam.distance_m;
        }
        vis::ok(err);
        return VIS_OK;
    })
}
