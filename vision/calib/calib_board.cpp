// calib_board.cpp: calibration from checkerboard views (intrinsics, distortion, scale, distance).
//
// OpenCV finds the inner corners (then refines them to sub-pixel) in every view and fits the
// pinhole model with distortion (calibrateCamera). With fewer than three views the full model is
// not determined, so the aspect ratio is held at 1 and the distortion at zero except k1 (one or two
// views still give focal length and pose); below six views the principal point stays at the image
// centre. The last view
// must show the board held in the ribbon's plane (y = 0): its pose gives the camera distance D (to
// where the optical axis meets that plane) and the camera's pitch, and px_per_mm = focal / D. Views
// at different tilts are needed for the focal length (and so D): fronto-parallel views alone fix
// only their ratio, px_per_mm.
#include "vis_internal.hpp"
#include "vis_calib.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <vector>

extern "C" vis_status vis_calib_from_checkerboard(vis_calib *c, const vis_frame *const *views,
                                                  size_t n_views, int cols, int rows, double square_mm,
                                                  vis_error *err)
{
    if (!c || !views || n_views < 1 || n_views > 200)
        return vis::fail(err, VIS_ERR_ARG, "checkerboard: need a calibration and 1..200 views");
    if (cols < 3 || rows < 3 || cols > 100 || rows > 100 || !vis::finite(square_mm) || square_mm <= 0)
        return vis::fail(err, VIS_ERR_ARG,
                         "checkerboard: need 3..100 inner corners per side and square_mm > 0");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        const cv::Size pattern(cols, rows);
        std::vector<std::vector<cv::Point3f>> obj;
        std::vector<std::vector<cv::Point2f>> img;
        cv::Size size;
        std::vector<cv::Point3f> board;
        for (int r = 0; r < rows; r++)
            for (int q = 0; q < cols; q++)
                board.emplace_back((float)(q * square_mm), (float)(r * square_mm), 0.f);
        for (size_t i = 0; i < n_views; i++) {
            if (!views[i] || views[i]->mat.empty())
                return vis::fail(err, VIS_ERR_ARG, "checkerboard: view %zu is empty", i);
            const cv::Mat g = vis::grey_of(views[i]->mat);
            if (i == 0)
                size = g.size();
            else if (g.size() != size)
                return vis::fail(err, VIS_ERR_ARG, "checkerboard: view %zu has another size", i);
            std::vector<cv::Point2f> corners;
            if (!cv::findChessboardCorners(g, pattern, corners,
                                           cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
                return vis::fail(err, VIS_ERR_NOT_FOUND,
                                 "checkerboard with %dx%d inner corners not found in view %zu", cols, rows,
                                 i);
            cv::cornerSubPix(g, corners, cv::Size(5, 5), cv::Size(-1, -1),
                             cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-3));
            img.push_back(corners);
            obj.push_back(board);
        }
        // Few views do not pin the principal point: a shift of it mimics a pitch of the camera, so
        // it stays at the image centre (with tangential distortion off) below six views.
        int flags = 0;
        if (n_views < 6)
            flags |= cv::CALIB_FIX_PRINCIPAL_POINT | cv::CALIB_ZERO_TANGENT_DIST;
        if (n_views < 3)
            flags |= cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_FIX_K2 | cv::CALIB_FIX_K3;
        cv::Mat K = cv::Mat::eye(3, 3, CV_64F), dist = cv::Mat::zeros(1, 5, CV_64F);
        K.at<double>(0, 2) = 0.5 * (size.width - 1);
        K.at<double>(1, 2) = 0.5 * (size.height - 1);
        std::vector<cv::Mat> rvecs, tvecs;
        const double rms = cv::calibrateCamera(obj, img, size, K, dist, rvecs, tvecs, flags,
                                               cv::TermCriteria(cv::TermCriteria::COUNT +
                                                                    cv::TermCriteria::EPS, 100, 1e-9));
        if (!std::isfinite(rms) || rms > 2.0)
            return vis::fail(err, VIS_ERR_FORMAT,
                             "checkerboard: calibration does not fit (reprojection error %.2f px)", rms);
        // Pose of the last view (the board in the ribbon's plane y = 0): the board normal, turned to
        // point away from the camera, is the world's +y axis in camera coordinates, (0, -sin t, cos t)
        // for a camera pitched down by t; the optical axis meets the plane at distance D = n.t / n_z.
        cv::Mat R;
        cv::Rodrigues(rvecs.back(), R);
        cv::Vec3d n(R.at<double>(0, 2), R.at<double>(1, 2), R.at<double>(2, 2));
        if (n[2] < 0)
            n = -n;
        const cv::Mat &tv = tvecs.back();
        const double D = (n[0] * tv.at<double>(0) + n[1] * tv.at<double>(1) + n[2] * tv.at<double>(2)) / n[2];
        if (!(D > 0) || !std::isfinite(D))
            return vis::fail(err, VIS_ERR_FORMAT, "checkerboard: the last view's pose is not in front of the camera");
        c->px_per_mm = K.at<double>(0, 0) / D;  // F = px_per_mm * D, the tracker's model
        c->camera_distance_mm = D;
        c->camera_tilt_rad = std::atan2(-n[1], n[2]);
        for (int i = 0; i < 9; i++)
            c->camera_matrix[i] = K.at<double>(i / 3, i % 3);
        for (int i = 0; i < 5; i++)
            c->dist[i] = dist.at<double>(0, i);
        c->has_intrinsics = 1;
        c->principal_px[0] = c->camera_matrix[2];
        c->principal_px[1] = c->camera_matrix[5];
        vis::ok(err);
        return VIS_OK;
    })
}
