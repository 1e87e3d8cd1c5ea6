/* vision.h: the C face of the vision module (C++17 and OpenCV 4.6 inside).
 *
 * It owns everything between a camera and two numbers per frame: frame sources (camera, video file,
 * image sequence, synthetic renderer) behind one interface, a synthetic renderer that draws a
 * simulated ribbon as a side view through a pinhole camera (with ground truth), an FFV1 video writer,
 * the tracker that measures the midpoint height Delta Z and the asymmetry A, and calibration.
 *
 * Design choices: every object is an opaque handle created by _create / _open functions and released by
 * _free / _close; every parameter set is a plain struct filled by a *_default() function, with units in
 * each field comment; every call that can fail returns a vis_status and fills an optional vis_error
 * with a human message (no C++ exception ever crosses this header; no global state; nothing exits).
 * The module does not know the simulator: a simulated state reaches it as a vis_shape (points and
 * normals in the simulator's frame), which the daemon fills.
 *
 * Conventions (DESIGN.md section 3, issue 5):
 * - World frame = simulator frame: x along the compression axis (left clamp point at x = 0), y along
 *   the ribbon width / shear direction, z up. Metres.
 * - The camera sits on the -y side at distance `distance_m` from the plane y = 0 and looks along +y,
 *   so it sees the x-z plane with x to the right and z up. Shear (+y) moves the right clamp away.
 * - Image: pixel (i, j) has its centre at (u, v) = (i, j) (OpenCV's convention); v points down.
 * - Arc length s runs from the left clamp in the image; angles are counterclockwise with z up.
 * - Delta Z = height of the arc-length midpoint above the line through the clamp points, over the free
 *   length l. A = 2 theta(1/2) - theta(0) - theta(1), theta the tangent angle. The *_cam variants use
 *   the curve projected orthographically on the x-z plane (what a distant side camera sees).
 */
#ifndef RIBBON_VISION_H
#define RIBBON_VISION_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- errors */

/* What went wrong, one code per kind of cause; the message in vis_error says which field or byte. */
typedef enum vis_status {
    VIS_OK = 0,
    VIS_ERR_ARG,         /* invalid argument: NULL, NaN/Inf, out of range, mismatched sizes */
    VIS_ERR_NOMEM,       /* allocation failed */
    VIS_ERR_IO,          /* file or device could not be opened, read or written */
    VIS_ERR_FORMAT,      /* content is damaged or not what was expected (video, image, calib file) */
    VIS_ERR_END,         /* end of a frame stream: not a failure, the normal way a loop stops */
    VIS_ERR_NOT_FOUND,   /* a pattern (checkerboard, clamp) was not found in the image */
    VIS_ERR_INTERNAL,    /* an unexpected exception inside OpenCV or the C++ runtime */
    VIS_ERR_TOO_LARGE    /* an image or video frame above VIS_MAX_IMAGE_SIDE / _PIXELS, refused
                            from its header before decoding */
} vis_status;

/* Largest image or video frame any reader decodes: a side, and the pixel count (64 Mpx: 8192 x
 * 8192). Larger ones are refused from their header (PNG, JPEG, BMP, PNM; a video's stream) with
 * VIS_ERR_TOO_LARGE before a decoder allocates for them. */
#define VIS_MAX_IMAGE_SIDE 16384
#define VIS_MAX_IMAGE_PIXELS 67108864.0

typedef struct vis_error {
    vis_status code;     /* same as the returned status */
    char message[256];   /* human-readable cause, NUL-terminated */
} vis_error;

const char *vis_status_str(vis_status s);

/* ---------------------------------------------------------------- frames */

/* An 8-bit image, 1 (grey) or 3 (BGR) channels, owned by the library. */
typedef struct vis_frame vis_frame;

vis_frame *vis_frame_alloc(int width_px, int height_px, int channels, vis_error *err);
void vis_frame_free(vis_frame *f);
int vis_frame_width(const vis_frame *f);
int vis_frame_height(const vis_frame *f);
int vis_frame_channels(const vis_frame *f);
size_t vis_frame_stride(const vis_frame *f);   /* bytes between rows */
uint8_t *vis_frame_data(vis_frame *f);         /* row-major pixels, `stride` bytes per row */
/* Copies src into dst (reallocated when its size or channels differ; no allocation otherwise). */
vis_status vis_frame_copy(const vis_frame *src, vis_frame *dst, vis_error *err);
/* Write/read an image file (format from the extension; PNG is lossless). Read resizes `f`. */
vis_status vis_frame_save(const vis_frame *f, const char *path, vis_error *err);
vis_status vis_frame_load(vis_frame *f, const char *path, vis_error *err);

/* ---------------------------------------------------------------- ribbon shape and ground truth */

/* A ribbon state in the simulator's frame: the free length only, point 0 at the left clamp point,
 * point n-1 at the right clamp point. Arrays are borrowed for the duration of the call. */
typedef struct vis_shape {
    size_t n;              /* number of centreline points, >= 3 */
    const double *pos;     /* 3n values: x, y, z of each point, metres */
    const double *normal;  /* 3n values: unit surface normal at each point (z-ish when flat) */
    double width_m;        /* ribbon width, metres (the band spans +-width/2 along normal x tangent) */
    double thickness_m;    /* ribbon thickness, metres (along the normal) */
} vis_shape;

typedef struct vis_truth {
    double length_m;       /* free length l: 3D arc length of the centreline, metres */
    double dz;             /* Delta Z from the 3D curve (midpoint height over the clamp line), / l */
    double a;              /* A from the 3D curve's tangent angle in its x-z projection... see below */
    double dz_cam;         /* Delta Z of the x-z projection (arc-length midpoint of the projection), / l */
    double a_cam;          /* A of the x-z projection, radians */
    double shear_m;        /* y of the right clamp point minus y of the left one, metres */
} vis_truth;
/* `a` is the paper's A: the tangent's elevation angle atan2(t_z, |t_xy|) integrated as
 * 2 theta(s=1/2) - theta(0) - theta(1) on the 3D curve (equal to a_cam when the curve is planar). */

vis_status vis_shape_truth(const vis_shape *shape, vis_truth *out, vis_error *err);

/* ---------------------------------------------------------------- pinhole camera */

typedef struct vis_camera {
    int width_px;          /* image width, pixels */
    int height_px;         /* image height, pixels */
    double focal_px;       /* focal length, pixels */
    double distance_m;     /* camera centre to the plane y = 0, metres (camera at y = -distance) */
    double tilt_rad;       /* pitch: positive looks down onto the scene, radians */
    double target_x_m;     /* the optical axis passes through (target_x, 0, target_z), metres */
    double target_z_m;
} vis_camera;

vis_camera vis_camera_default(void);
/* Project a world point (metres) to pixel coordinates. Fails if the point is behind the camera. */
vis_status vis_camera_project(const vis_camera *cam, const double p[3], double uv[2], vis_error *err);
/* Set focal_px and the target so that the box [x0,x1] x [z0,z1] (plane y = 0, metres) fills `fill`
 * (0..1) of the image width or height, whichever is tighter. */
vis_status vis_camera_fit(vis_camera *cam, double x0, double x1, double z0, double z1, double fill,
                          vis_error *err);

/* ---------------------------------------------------------------- synthetic renderer */

typedef struct vis_render_params {
    vis_camera camera;
    double background;        /* backdrop grey level, 0..255 */
    double ribbon;            /* ribbon grey level, 0..255 (darker or lighter than the backdrop) */
    double clamp;             /* clamp jaw grey level, 0..255 */
    double clamp_length_m;    /* jaw length along the ribbon, outside the free length, metres (0 = none) */
    double clamp_height_m;    /* jaw height across the ribbon, metres */
    double noise_sigma;       /* additive Gaussian noise, grey levels (0 = none) */
    double blur_sigma_px;     /* Gaussian optical blur, pixels (0 = none) */
    double light_gradient;    /* illumination changes by this fraction across the width (0 = even) */
    double vignette;          /* illumination falls by this fraction at the corners (0 = none) */
    int clutter;              /* number of random background shapes (0 = none) */
    int supersample;          /* anti-aliasing: samples per pixel side, 1..8 */
    uint64_t seed;            /* seed of the noise and clutter generator (no hidden global RNG) */
} vis_render_params;

vis_render_params vis_render_params_default(void);

/* Where the renderer put things, in pixels (the image-side ground truth of one frame). */
typedef struct vis_render_truth {
    vis_truth truth;          /* the shape's ground truth */
    double clamp_left_px[2];  /* projected left clamp point (u, v) */
    double clamp_right_px[2]; /* projected right clamp point (u, v) */
    double mid_px[2];         /* projected 3D arc-length midpoint (u, v) */
    double px_per_m;          /* focal_px / distance_m: the scale in the plane y = 0, pixels/metre */
} vis_render_truth;

typedef struct vis_renderer vis_renderer;
vis_renderer *vis_renderer_create(const vis_render_params *p, vis_error *err);
void vis_renderer_free(vis_renderer *r);
/* Draw one frame into `out` (reallocated to the camera size, 1 channel). `truth` may be NULL. */
vis_status vis_renderer_draw(vis_renderer *r, const vis_shape *shape, vis_frame *out,
                             vis_render_truth *truth, vis_error *err);

/* ---------------------------------------------------------------- video writing */

/* Lossless video. By the name's ending: .mkv = FFV1 in Matroska (compressed, 16.7 ms per 1280x720
 * grey frame on one core); .avi = raw Y800 (uncompressed 8-bit grey, 1 byte per pixel) in AVI, about
 * 0.3 ms per frame, what live trials record. Both read back bit-exact. */
typedef struct vis_video_writer vis_video_writer;
vis_video_writer *vis_video_writer_open(const char *path, int width_px, int height_px, int channels,
                                        double fps, vis_error *err);
/* Raw 8-bit grey Y800 in AVI (.avi): bit-exact too, and no CPU to encode or decode (what a rig
 * recording in real time would write). Same write and close calls. */
vis_video_writer *vis_video_writer_open_y800(const char *path, int width_px, int height_px, double fps,
                                             vis_error *err);
vis_status vis_video_writer_write(vis_video_writer *w, const vis_frame *f, vis_error *err);
void vis_video_writer_close(vis_video_writer *w);

/* Render a sequence of shapes into OUT.mkv plus a ground-truth CSV beside it, one row per frame:
 * frame,t_s,shear_m,length_m,dz,a,dz_cam,a_cam,clamp_left_u,clamp_left_v,clamp_right_u,
 * clamp_right_v,mid_u,mid_v,px_per_m */
typedef struct vis_synth_writer vis_synth_writer;
vis_synth_writer *vis_synth_writer_open(const char *video_path, const char *truth_csv_path,
                                        const vis_render_params *p, double fps, vis_error *err);
vis_status vis_synth_writer_add(vis_synth_writer *w, const vis_shape *shape, vis_render_truth *truth,
                                vis_error *err);
/* Flushes and closes; returns the first error met while closing. */
vis_status vis_synth_writer_close(vis_synth_writer *w, vis_error *err);

/* ---------------------------------------------------------------- frame sources */

typedef struct vis_camera_settings {
    int index;                /* V4L2 device index (used when path is NULL or empty) */
    const char *path;         /* device path such as /dev/video0, or NULL */
    int width_px;             /* requested width, pixels (0 = driver default) */
    int height_px;            /* requested height, pixels (0 = driver default) */
    double fps;               /* requested frame rate, 1/s (0 = driver default) */
    char fourcc[5];           /* requested pixel format such as "MJPG" ("" = driver default) */
    /* GenICam (Aravis) cameras only: aravis = 1 opens `path` as an Aravis device id ("" or NULL =
     * the first camera found). Mono8 always; 0 / negative = leave the camera's own setting. */
    int aravis;
    int offset_x_px, offset_y_px; /* ROI origin on the sensor, pixels (-1 = leave) */
    double exposure_us;           /* ExposureTime, microseconds (0 = leave) */
    double gain_db;               /* Gain, dB (< 0 = leave) */
    int n_buffers;                /* stream buffers (0 = 32) */
} vis_camera_settings;
vis_camera_settings vis_camera_settings_default(void);

/* Synthetic source: the callback fills `shape` for frame `index` (arrays must stay valid until the
 * next call) and returns 0, or returns 1 at the end of the sequence, or -1 on error. */
typedef int (*vis_shape_fn)(void *user, int index, vis_shape *shape);

typedef struct vis_source vis_source;
vis_source *vis_source_open_camera(const vis_camera_settings *s, vis_error *err);
vis_source *vis_source_open_video(const char *path, vis_error *err);
/* The same video decoded ahead on a thread of its own (up to 16 frames), so decoding runs while the
 * caller tracks: the frames, their order, times and errors are exactly vis_source_open_video's
 * (vision/source_prefetch.cpp). For replays and `ribbonctl track`, which use every core this way. */
vis_source *vis_source_open_video_prefetch(const char *path, vis_error *err);
/* printf-style pattern with one integer conversion, e.g. "dir/frame_%04d.png", starting at `first`. */
vis_source *vis_source_open_images(const char *pattern, int first, vis_error *err);
vis_source *vis_source_open_synthetic(const vis_render_params *p, double fps, vis_shape_fn fn,
                                      void *user, vis_error *err);
/* Next frame as grey into `out` (reallocated as needed); `t_s` (may be NULL) gets its time in seconds.
 * Returns VIS_ERR_END at a clean end; VIS_ERR_FORMAT when the stream is damaged (a video that stops
 * before its announced length, an unreadable image): the message says after which frame. */
vis_status vis_source_read(vis_source *src, vis_frame *out, double *t_s, vis_error *err);
/* What a live camera says about one frame (vis_source_read_meta).
 * camera_t_s: the camera's own timestamp of the frame, seconds on the camera's clock (GenICam buffer
 *   timestamp; V4L2 buffer timestamp, CLOCK_MONOTONIC for UVC); NaN when the source has none.
 * host_t_s: CLOCK_MONOTONIC when the frame was handed to the program (seconds).
 * frame_id: the camera's frame counter (GenICam block id); sources without one count frames.
 * lost_before: frames that never arrived just before this one (a gap in the camera's ids).
 * incomplete: buffers the transport delivered damaged (missing packets, timeout) just before this
 *   one; they are dropped unread (their pixels are not an image). */
typedef struct vis_frame_meta {
    double camera_t_s;
    double host_t_s;
    uint64_t frame_id;
    long lost_before;
    int incomplete;
} vis_frame_meta;
/* A camera's block ids, followed to count the frames that never arrived. GigE Vision 1.x ids are
 * 16 bits and wrap 65535 -> 1 (0 is never used); GigE Vision 2 and USB3 Vision ids are 64 bits.
 * A transport may deliver a frame late, after a newer one (a buffer with missing packets is closed
 * when its timeout runs out, after the frames behind it completed): its id was already counted in
 * the gap before the newer frame, so it is late, counted nowhere again, and the ids' position stays
 * at the newest frame. */
typedef struct vis_block_ids {
    int have;      /* an id was seen */
    uint64_t last; /* the newest id seen */
} vis_block_ids;
#define VIS_BLOCK_LATE (-1L)
/* The frames lost just before `id` (0 or more), or VIS_BLOCK_LATE for an id at most 1,024 behind
 * the newest one seen (a late or repeated buffer; in the 16-bit range also just across a wrap).
 * Further back is a 16-bit wrap (the ids' last value at most 65535) or, for 64-bit ids, the camera
 * starting its ids again (0 lost). */
long vis_block_ids_next(vis_block_ids *ids, uint64_t id);

/* Like vis_source_read, with the frame's metadata. A source that is not a live camera gives
 * camera_t_s = its own time (t_s) and counts frames. */
vis_status vis_source_read_meta(vis_source *src, vis_frame *out, vis_frame_meta *meta, vis_error *err);
/* Lists the GenICam cameras Aravis sees: calls fn once per camera with its device id, vendor, model,
 * and transport ("GigEVision", "USB3Vision"); returns how many, or -1 with err when Aravis cannot
 * enumerate. */
int vis_aravis_list(void (*fn)(void *user, const char *id, const char *vendor, const char *model,
                               const char *protocol),
                    void *user, vis_error *err);
int vis_source_frame_count(const vis_source *src);  /* announced count, or -1 if unknown */
double vis_source_fps(const vis_source *src);       /* frames per second, or 0 if unknown */
void vis_source_close(vis_source *src);

/* ---------------------------------------------------------------- calibration */

/* Maps pixels to millimetres in the plane y = 0 of the rig and names the clamp points. */
typedef struct vis_calib {
    double px_per_mm;          /* scale in the plane y = 0, pixels per millimetre */
    double clamp_left_px[2];   /* left clamp point (u, v) at zero shear, pixels */
    double clamp_right_px[2];  /* right clamp point (u, v) at zero shear, pixels */
    double principal_px[2];    /* principal point (u, v), pixels; negative = image centre */
    double camera_distance_mm; /* camera centre to where its optical axis meets the plane y = 0, mm;
                                  0 = unknown: no depth correction, no tilt */
    double camera_tilt_rad;    /* camera pitch, radians, positive looks down (as vis_camera) */
    int has_intrinsics;        /* 1 when camera_matrix and dist are valid (checkerboard) */
    double camera_matrix[9];   /* 3x3 row-major intrinsic matrix, pixels */
    double dist[5];            /* OpenCV distortion k1 k2 p1 p2 k3, dimensionless */
} vis_calib;

vis_calib vis_calib_default(void);
/* Scale from the two clamp points and their known spacing (mm) at zero shear. */
vis_status vis_calib_from_clamps(vis_calib *c, const double left_px[2], const double right_px[2],
                                 double spacing_mm, vis_error *err);
/* Intrinsics, distortion and scale from views of a checkerboard with `cols` x `rows` inner corners
 * and `square_mm` squares; the last view must show the board in the plane y = 0 (sets px_per_mm). */
vis_status vis_calib_from_checkerboard(vis_calib *c, const vis_frame *const *views, size_t n_views,
                                       int cols, int rows, double square_mm, vis_error *err);
/* The calibration that matches a synthetic camera (mock mode): clamp points projected at zero shear
 * from the world points `left_m`, `right_m` (metres; their y is ignored), scale and distance from
 * the camera, tilt included. */
vis_status vis_calib_from_camera(vis_calib *c, const vis_camera *cam, const double left_m[3],
                                 const double right_m[3], vis_error *err);
vis_status vis_calib_check(const vis_calib *c, vis_error *err);
vis_status vis_calib_save(const vis_calib *c, const char *path, vis_error *err);
vis_status vis_calib_load(vis_calib *c, const char *path, vis_error *err);

/* ---------------------------------------------------------------- tracker */

typedef enum vis_polarity {
    VIS_POLARITY_AUTO = 0,     /* decided from the frame (and kept once the ribbon is found) */
    VIS_POLARITY_DARK,         /* dark ribbon on a light (backlit) background */
    VIS_POLARITY_LIGHT         /* light ribbon on a dark background */
} vis_polarity;

/* Why a frame has no measurement. */
typedef enum vis_reason {
    VIS_REASON_NONE = 0,       /* measured */
    VIS_REASON_UNREADABLE,     /* the frame could not be read or decoded */
    VIS_REASON_DARK,           /* the frame is (nearly) black: no contrast */
    VIS_REASON_SATURATED,      /* the frame is (nearly) saturated: no contrast */
    VIS_REASON_CLAMP_NOT_FOUND,/* the clamp points are unknown or outside the image */
    VIS_REASON_LOST,           /* no ribbon-like ridge joins the clamps */
    VIS_REASON_OCCLUDED,       /* the ridge is broken over part of its length */
    VIS_REASON_NOISE,          /* the frame is noise: neighbouring pixels unrelated, no structure */
    VIS_REASON_NO_RIBBON       /* no ribbon-like ridge leaves the clamps anywhere in the frame */
} vis_reason;
const char *vis_reason_str(vis_reason r);

typedef struct vis_track_params {
    double length_mm;          /* free length l used to normalise Delta Z, mm (0 = measured) */
    vis_polarity polarity;     /* which way the ribbon contrasts with the background */
    double band_px;            /* half-width of the search band around the guide curve, pixels (12) */
    double ribbon_max_px;      /* largest apparent ribbon thickness, pixels (8): thicker ridges are
                                  refused; also sets the background filter */
    double step_px;            /* spacing of centreline samples along the arc, pixels (1) */
    double end_margin_px;      /* samples closer than this to a clamp point are not traced, px (3) */
    double fit_window;         /* half-window of the interior local fits, fraction of the length (0.08) */
    double end_window;         /* one-sided window of the end-tangent fits, fraction of length (0.09:
                                  less noise in A than 0.06, docs/vision-acquisition-and-replay-speed.md) */
    double min_contrast;       /* weakest ridge accepted, grey levels (12) */
    double min_quality;        /* below this quality (0..1) a frame is reported LOST (0.3) */
    double min_bend_ratio;     /* a curve whose tightest radius of curvature is below this many
                                  median ridge widths, where the strip shows its face (median
                                  ridge 2 px wider than its narrowest tenth), is not measured by
                                  cross-section centroids, unless it is nearly symmetric (|A|
                                  below 0.1 rad) at a ratio of 1.25 or more; below 1 always. Such
                                  bends are measured with a model of the band's silhouette when
                                  no other attempt measures the frame, and the frame is LOST if
                                  the model does not explain the pixels (2, the default; 0 = off,
                                  the model never runs: docs/vision-acquisition-and-replay-speed.md) */
    int refresh_frames;        /* every this many frames (counted by vis_tracker_process since the
                                  tracker was made or reset) the previous curve is forgotten and the
                                  frame acquired from scratch, as after vis_tracker_reset: no drift
                                  of following outlives it, and a recording splits there into
                                  stretches that track on separate cores with the serial results
                                  (vis_track_pipe). 0 = never; 0..100000 (100) */
} vis_track_params;
vis_track_params vis_track_params_default(void);

/* Find the two clamp points in a frame: where the ribbon leaves each clamp jaw, at the ribbon's
 * centre, sub-pixel (vision/clamps.cpp). The jaws are the two thick blobs that contrast with the
 * backdrop the way the ribbon does and that the ribbon joins; `p` (NULL = defaults) gives the
 * polarity (AUTO decides from the frame), ribbon_max_px (thicker than this counts as a jaw) and
 * min_contrast. `left_px` is the one further left in the image. `quality` (may be NULL) gets 0..1:
 * share of the ribbon seen leaving each jaw / (1 + (spread of the jaw face / 0.5 px)^2), the worse
 * jaw. Under perspective the point sits about |u - u0| w / (2 D) px toward the image centre (the
 * jaw's silhouette face is its face nearer the optical axis; w the jaw depth, D the distance).
 * Returns VIS_ERR_NOT_FOUND with the cause in `err` when no clamp pair is found (no jaws, one jaw,
 * no ribbon between them, a black or saturated frame). */
vis_status vis_find_clamps(const vis_frame *f, const vis_track_params *p, double left_px[2],
                           double right_px[2], double *quality, vis_error *err);

typedef struct vis_measure {
    vis_reason reason;         /* VIS_REASON_NONE when dz and a are valid */
    double dz;                 /* Delta Z, normalised by l (positive up) */
    double a;                  /* A, radians */
    double quality;            /* 0..1: share of the arc with a clear ridge / (1 + (residual / 0.5 px)^2) */
    double length_mm;          /* measured (projected, depth-corrected) arc length, mm */
    double mid_px[2];          /* arc-length midpoint in the image, pixels */
    double residual_px;        /* median distance of the traced samples from the smooth fit, pixels */
} vis_measure;

typedef struct vis_tracker vis_tracker;
vis_tracker *vis_tracker_create(const vis_track_params *p, const vis_calib *c, vis_error *err);
void vis_tracker_free(vis_tracker *t);
/* Measure one frame. `shear_mm` is the right clamp's rail position along y at this frame (away from
 * the camera positive), used for the depth correction. A frame that cannot be measured is not an
 * error: the call returns VIS_OK with out->reason set. Errors are for bad arguments only. */
vis_status vis_tracker_process(vis_tracker *t, const vis_frame *f, double shear_mm, vis_measure *out,
                               vis_error *err);
/* Report an unreadable frame (keeps the tracker's state consistent). */
void vis_tracker_skip(vis_tracker *t, vis_measure *out);
/* The last smooth centreline in pixels, from the left clamp: copies up to `max` (u, v) pairs into
 * `uv` and returns how many exist. */
size_t vis_tracker_curve(const vis_tracker *t, double *uv, size_t max);
/* The centreline's depth along the ribbon for the frames that follow, from a prediction of their
 * shape (the trial's own simulation): n points of (frac[i], depth_rel[i]), frac the arc fraction
 * along the ribbon (material arc length / l) from 0 at the left clamp to 1 at the right one,
 * strictly increasing, depth_rel the depth away from the camera over the shear (0 at the left
 * clamp, 1 at the right one; |depth_rel| <= VIS_DEPTH_REL_MAX). Each frame maps it onto the projected arc it
 * measures with its own shear and the known length. n = 0 restores the default profile, shear
 * (3 xi^2 - 2 xi^3), which the DER strip is nowhere near under shear (docs/vision.md, "Depth").
 * Kept across vis_tracker_reset. VIS_ERR_ARG (with the reason) for a profile that is not one; the
 * tracker's profile is then unchanged. */
#define VIS_DEPTH_REL_MAX 10.0 /* largest |depth / shear| a profile may hold */
vis_status vis_tracker_set_depth_profile(vis_tracker *t, const double *frac, const double *depth_rel,
                                         size_t n, vis_error *err);
/* Shapes a prediction of the trial expects (its simulation's states: before, during and after the
 * snap), from which the tracker takes each frame's depth: n_shapes shapes of n_points points,
 * shape i keyed by shear_mm[i] (the right clamp's shear, as vis_tracker_process takes it), dz[i]
 * and a[i] (Delta Z / l and A of the shape's x-z projection, as the camera sees them: the
 * simulator's dz_cam and a_cam), its profile frac[i n_points + j], depth_rel[i n_points + j] as
 * vis_tracker_set_depth_profile takes one. */
typedef struct vis_depth_library {
    size_t n_shapes, n_points;
    const double *shear_mm, *dz, *a;
    const double *frac, *depth_rel;
    const double *xz_mm;   /* NULL, or n_shapes x n_points x 2: each point's (x, z) relative to the
                              left clamp point, mm (the shape's x-z projection): then the nearest
                              shape is the one whose projection is nearest the frame's curve */
} vis_depth_library;
/* With a library (copied in; NULL or n_shapes 0 removes it), every measured frame is measured again
 * with the depth of the library's shape nearest to what it measured, starting from the last
 * frame's; the shape stays for the next frame. Nearest: with xz_mm, the shear (in units of 2 mm)
 * and the RMS distance between the frame's curve and the shape's projection, 16 points evenly along
 * each (in units of 0.5 mm); without, the shear, Delta Z (0.005) and A (0.02 rad).
 * A single side camera cannot see depth and the shapes through a snap differ in it: at 1 m the
 * default profile puts 26 of 46 frames of three simulated trials more than 2 px or 0.1 rad off, a
 * library from another run of the same trials none; one whose snap comes 0.8 mm of shear later,
 * 21 (docs/vision.md, "Depth"). VIS_ERR_ARG with the reason for a library that is not one (the old
 * one stays). A profile set by vis_tracker_set_depth_profile is replaced at the next frame. */
vis_status vis_tracker_set_depth_library(vis_tracker *t, const vis_depth_library *lib, vis_error *err);
/* Forget the previous curve (the next frame is searched from scratch), the polarity when it is
 * AUTO, and a library's shape (back to the profile of vis_tracker_set_depth_profile); the count of
 * refresh_frames starts again. */
void vis_tracker_reset(vis_tracker *t);

/* Frames tracked on several cores with the serial results (vision/track_pipe.cpp). The caller
 * pushes frames in order and pops their results in the same order. The stretches between the
 * tracker's refresh points (vis_track_params.refresh_frames, and every push with `reset`) go to
 * `threads` workers (0 = one per core; at most capacity / refresh_frames + 1, since only that many
 * stretches fit in the pipe at once), each tracking on its own copy of `t`: every result is bit
 * for bit what vis_tracker_process(t, ...) gives on the same frames in a serial loop that goes on
 * from t as it is at create and calls vis_tracker_reset(t) where `reset` is set. With
 * refresh_frames 0 there is one stretch and one worker (tracking then only overlaps the caller's
 * decoding). `t` is copied at create and must not be used meanwhile; vis_track_pipe_free puts back
 * into it the state the serial loop ends in (reset instead when frames were left unpopped). The
 * pipe holds at most vis_track_pipe_capacity frames: (threads + 1) refresh_frames, 16 to 256.
 * One thread calls push and pop. */
typedef struct vis_track_pipe vis_track_pipe;
vis_track_pipe *vis_track_pipe_create(vis_tracker *t, int threads, vis_error *err);
void vis_track_pipe_free(vis_track_pipe *p);
size_t vis_track_pipe_capacity(const vis_track_pipe *p);
size_t vis_track_pipe_held(const vis_track_pipe *p);   /* pushed and not yet popped */
int vis_track_pipe_workers(const vis_track_pipe *p);
/* Hand frame `f` over with its shear (see vis_tracker_process); `reset` forgets before it. The
 * pixels move into the pipe without a copy: `f` comes back holding another buffer (contents
 * undefined, often of the same size, ready to be read into). VIS_ERR_ARG when the pipe is full
 * (pop first), for a NULL or empty frame, or a shear that is not finite. */
vis_status vis_track_pipe_push(vis_track_pipe *p, vis_frame *f, double shear_mm, int reset, vis_error *err);
/* The oldest frame's result: its status is the return value (VIS_OK, or the error that
 * vis_tracker_process gave on it, in err), its measure in *m, its centreline in uv (up to max_uv
 * (u, v) pairs; *n_uv the count, as vis_tracker_curve), and the frame itself moved into `frame`
 * (may be NULL; its old buffer goes back to the pipe). Waits for it when `wait`; otherwise
 * VIS_ERR_NOT_FOUND when it is not done yet. VIS_ERR_END when the pipe holds no frame. */
vis_status vis_track_pipe_pop(vis_track_pipe *p, int wait, vis_measure *m, double *uv, size_t max_uv,
                              size_t *n_uv, vis_frame *frame, vis_error *err);

/* Track every frame of the video at `path` (up to max_frames) with `t`, in order, into out[0..],
 * starting with vis_tracker_reset(t): `threads` 1 is the plain serial loop; any other value tracks
 * the stretches between refresh points on `threads` cores (0 = all): on a raw grey (Y800) file each
 * worker reads the file itself, passing over the others' frames; other formats decode ahead on
 * another thread (vis_source_open_video_prefetch) into vis_track_pipe. out[i] is exactly what
 * vis_tracker_process gives on frame i in the serial loop, and `t` ends in the same state; after a
 * failure (damage, or the tracker's error on a frame, which ends the run there) `t` is reset.
 * shear_mm[i] (NULL or i >= n_shear: 0) is frame i's shear. *n_frames gets the frames done; a
 * damaged video returns its error after the frames before the damage (vision/track_video.cpp). */
vis_status vis_track_video(const char *path, vis_tracker *t, const double *shear_mm, size_t n_shear,
                           int threads, vis_measure *out, size_t max_frames, size_t *n_frames,
                           vis_error *err);

/* Draw the tracked centreline, midpoint and values over `in` into `out` (3-channel). */
vis_status vis_overlay_draw(const vis_frame *in, const vis_tracker *t, const vis_measure *m, int frame,
                            vis_frame *out, vis_error *err);
/* The same with the centreline given: n (u, v) pairs (as vis_track_pipe_pop hands them out). */
vis_status vis_overlay_draw_curve(const vis_frame *in, const double *uv, size_t n, const vis_measure *m, int frame,
                                  vis_frame *out, vis_error *err);

/* Index of the first frame after a jump in Delta Z, or -1. A jump is a change between consecutive
 * measured frames larger than `min_jump` (normalised) and than `fraction` of the overall range. */
int vis_snap_find(const double *dz, const unsigned char *valid, size_t n, double min_jump,
                  double fraction);

#ifdef __cplusplus
}
#endif

#endif
