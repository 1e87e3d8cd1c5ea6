/* vis_track.h: the face of vision/track/: the tracker that measures Delta Z and A in each frame
 * (tracker.cpp, its stages in tracker_impl.hpp, one file each), the clamp points found in a frame
 * (clamps.cpp), frames tracked on several cores (track_pipe.cpp), a whole video tracked
 * (track_video.cpp), the overlay drawn over a frame (overlay.cpp) and the snap found in a tracked
 * series (snap.cpp). Why a frame has no measurement (vis_reason) is in vis_core.h. */
#ifndef RIBBON_VIS_TRACK_H
#define RIBBON_VIS_TRACK_H

#include "vis_calib.h"
#include "vis_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- tracker */

typedef enum vis_polarity {
    VIS_POLARITY_AUTO = 0,     /* decided from the frame (and kept once the ribbon is found) */
    VIS_POLARITY_DARK,         /* dark ribbon on a light (backlit) background */
    VIS_POLARITY_LIGHT         /* light ribbon on a dark background */
} vis_polarity;

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
/* The defaults for a ribbon `width_mm` wide seen at `px_per_mm`: a strip that twists shows its
 * face, so ribbon_max_px is the face's apparent width plus 2 px (rounded up) and band_px 1.5 times
 * that, neither below the defaults nor above 100. A width or scale that is not positive and finite
 * gives the defaults. */
vis_track_params vis_track_params_for_ribbon(double width_mm, double px_per_mm);

/* Find the two clamp points in a frame: where the ribbon leaves each clamp jaw, at the ribbon's
 * centre, sub-pixel (vision/track/clamps.cpp). The jaws are the two thick blobs that contrast with the
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
/* The points the last smooth centreline was fitted to, in pixels as vis_tracker_curve's: the left
 * clamp point, the tracer's valid samples in order along the arc (about step_px apart), the right
 * clamp point; 0 when the last frame was not measured. The smooth fit (fit_window) rounds a sharp
 * crease off and, with a crease inside its end window, moves the curve's ends off the clamp points
 * (on the mock trial's -86 deg creases 0.002-0.004 l near them: docs/calibration.md); these points
 * follow the crease, for a shape compared point by point (the fit's centreline, sim.fit_shape).
 * Copies up to `max` (u, v) pairs into `uv` and returns how many exist. */
size_t vis_tracker_samples(const vis_tracker *t, double *uv, size_t max);
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

/* Frames tracked on several cores with the serial results (vision/track/track_pipe.cpp). The caller
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
 * damaged video returns its error after the frames before the damage (vision/track/track_video.cpp). */
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
