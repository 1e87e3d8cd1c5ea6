/*
 * plot.h: the lab's figures as PNG files, drawn with PLplot (pngcairo device).
 *
 * Pure functions: plain arrays in, one PNG file out. No database, no simulator: callers
 * (ribbonctl report / phase-report, the API's report.png, ribbon-sim continue --plot and
 * sweep --plot) gather the numbers and pass them here. The one PLplot stack of the project.
 *
 *   plot_trial_report   one trial: Delta Z and A against Delta W, measured and predicted, snaps marked
 *   plot_phase_report   the predicted (Gamma, phi) phase diagram with every trial's measured regime
 *   plot_branches       continuation branches: stable black, unstable grey, pitchfork circles,
 *                       saddle-node squares (the paper's figures 3a and 4a); plot_branches_panels
 *                       puts several side by side (ribbon-sim continue --plot)
 *   plot_sweep          a sweep's regime map: a marker per point, the located boundaries
 *   plot_boundary       named coloured curves over a sweep's points, an optional special point:
 *                       the traced regime boundary, fold and pitchfork curves (ribbon-sim boundary)
 *
 * Conventions shared by all of them:
 *   - Quantities are the paper's normalised ones: Delta W = dw/l, Delta Z = dz/l (dimensionless),
 *     A in rad, Gamma as a fraction of the free length l, phi in degrees.
 *   - NaN in a data array is a gap: the point is skipped and a line is broken there, never drawn
 *     through. +-Inf is refused as bad input (it is never a legitimate measurement).
 *   - width_px / height_px of 0 mean the default (PLOT_WIDTH_DEFAULT x PLOT_HEIGHT_DEFAULT).
 *   - Titles, labels and regime texts are PLplot text: UTF-8, with PLplot's escapes ("#gD" is
 *     Delta, "#gG" Gamma, "#gf" phi, "#u"/"#d" super/subscript); a literal '#' is written "##".
 *   - The file is written to a temporary name in the same directory, checked (PNG signature, size,
 *     final IEND chunk) and renamed over png_path, so a failed plot never leaves a half file.
 *   - Every failure returns a status and a human reason in why (NUL-terminated, truncated to
 *     why_len). Nothing here calls exit(): PLplot's fatal errors are caught (see plot_session.c).
 *   - Safe to call repeatedly and from several threads: PLplot's global state is serialised by one
 *     lock, and every figure gets its own PLplot stream, ended before return.
 */
#ifndef RIBBON_PLOT_H
#define RIBBON_PLOT_H

#include <stdbool.h>
#include <stddef.h>

#define PLOT_WIDTH_DEFAULT 1200 /* px */
#define PLOT_HEIGHT_DEFAULT 900 /* px */
#define PLOT_SIZE_MIN 200       /* px, either side */
#define PLOT_SIZE_MAX 8000      /* px, either side */

typedef enum plot_status {
    PLOT_OK = 0,
    PLOT_ERR_ARG,    /* invalid input: NULL, Inf, out of range, unsorted axis, size mismatch */
    PLOT_ERR_IO,     /* the output file could not be created, written, verified or renamed */
    PLOT_ERR_DEVICE, /* the PLplot pngcairo driver is not installed or could not be loaded */
    PLOT_ERR_PLPLOT  /* PLplot reported an error (abort or fatal exit) while drawing */
} plot_status;

/* Snap regimes, as the sim and the store name them ("asymmetric", "symmetric", "none"/"no snap"). */
typedef enum plot_regime {
    PLOT_REGIME_UNKNOWN = 0, /* failed run, not classified, or not known */
    PLOT_REGIME_ASYMMETRIC,  /* pitchfork first: snaps through an asymmetric shape */
    PLOT_REGIME_SYMMETRIC,   /* saddle-node first: snaps symmetrically */
    PLOT_REGIME_NO_SNAP,     /* shear limit reached without a snap */
    PLOT_REGIME_NO_UPPER     /* no stable upper state to snap from (a located fold or pitchfork ends it) */
} plot_regime;

/* "asymmetric", "symmetric", "none" / "no snap" / "no-snap" / "no_snap" (case-insensitive);
 * anything else (and NULL) is PLOT_REGIME_UNKNOWN. */
plot_regime plot_regime_parse(const char *s);
/* "asymmetric", "symmetric", "no snap", "unknown". */
const char *plot_regime_name(plot_regime r);

/* One curve against Delta W: n samples, dw[i], dz[i], a[i]; NaN in any entry is a gap.
 * a may be NULL (no asymmetry known): the A panel then shows only the other curve. */
typedef struct plot_curve {
    const double *dw; /* Delta W = dw/l, dimensionless */
    const double *dz; /* Delta Z = dz/l, dimensionless */
    const double *a;  /* asymmetry A, rad (may be NULL) */
    size_t n;
} plot_curve;

/* plot_trial_report: two stacked panels sharing the Delta W axis, Delta Z (top) and A (bottom).
 * Measured: solid line with sample points; predicted: dashed line; each snap a vertical line in
 * both panels, annotated with its value; legend on the right. */
typedef struct plot_trial_data {
    const char *title;            /* e.g. "trial 12: PET-3, phi = 90 deg, Gamma = 0.13"; NULL ok */
    plot_curve measured;          /* from the camera; n may be 0 */
    plot_curve predicted;         /* from the simulator; n may be 0 */
    double snap_dw_measured;      /* Delta W at the measured snap; NaN = no snap */
    double snap_dw_predicted;     /* Delta W at the predicted snap; NaN = no snap */
    const char *regime_measured;  /* free text shown in the legend; NULL = unknown */
    const char *regime_predicted; /* free text shown in the legend; NULL = unknown */
    /* The calibrated prediction (issue 32 B): its snap drawn as a line with its 1-sigma band
     * shaded behind the curves; NaN = none (no band: sd NaN). */
    double snap_dw_calibrated, snap_sd_calibrated;
    const char *regime_calibrated; /* free text shown in the legend; NULL = unknown */
    int width_px, height_px;      /* 0 = default */
} plot_trial_data;

/* Everything empty, snaps NaN, default size. */
void plot_trial_data_default(plot_trial_data *d);
plot_status plot_trial_report(const char *png_path, const plot_trial_data *d, char *why, size_t why_len);

/* One trial's measured point on the phase diagram. NaN gamma or phi: the trial is skipped. */
typedef struct plot_phase_trial {
    double gamma;       /* crease position Gamma, fraction of l */
    double phi_deg;     /* crease angle phi, degrees */
    plot_regime regime; /* measured regime */
} plot_phase_trial;

/* The boundary the experiments support at one phi (ribbonctl phase): a bar from lo to hi (a NaN
 * side is open: the bar runs to the axis there, dotted) and, when gamma is finite, a marker at the
 * estimate; the finite estimates are joined by a solid line. Bluish green. */
typedef struct plot_phase_edge {
    double phi_deg;
    double gamma;  /* estimate; NaN = none */
    double lo, hi; /* interval; NaN = open on that side; both NaN: not drawn */
} plot_phase_edge;

/* plot_phase_report: x = Gamma, y = phi (deg). The predicted grid is drawn as shaded cells
 * (cell edges halfway between neighbouring sweep points), the predicted boundary Gamma*(phi) as a
 * dashed black line, trials as markers: filled squares asymmetric, open circles symmetric,
 * crosses no snap, diamonds unknown. Legend on the right.
 *
 *   grid layout: regime of (gamma[i], phi_deg[j]) is grid[j * n_gamma + i]
 *   (one row per phi, as a sweep over phi then Gamma writes it). */
typedef struct plot_phase_data {
    const char *title;                /* NULL ok */
    const double *gamma;              /* n_gamma sweep values, strictly increasing, finite */
    size_t n_gamma;                   /* 0 = no predicted grid */
    const double *phi_deg;            /* n_phi sweep values (deg), strictly increasing, finite */
    size_t n_phi;                     /* 0 = no predicted grid */
    const plot_regime *grid;          /* n_phi * n_gamma predicted regimes (layout above) */
    const double *boundary_gamma;     /* predicted boundary points Gamma*(phi); NaN = gap */
    const double *boundary_phi_deg;   /* their phi (deg); NaN = gap */
    size_t n_boundary;                /* 0 = no boundary curve */
    const plot_phase_trial *trials;   /* measured trials */
    size_t n_trials;
    const int *trial_counts;          /* NULL, or n_trials counts: the trials a marker stands for;
                                         2 or more is written beside it ("x3") */
    const plot_phase_edge *edges;     /* experimental boundary, one per phi (NULL: none) */
    size_t n_edges;
    int width_px, height_px;          /* 0 = default */
} plot_phase_data;

void plot_phase_data_default(plot_phase_data *d);
plot_status plot_phase_report(const char *png_path, const plot_phase_data *d, char *why, size_t why_len);

/* A continuation branch: n points (x[i], y[i]) in order along the branch; stable[i] tells
 * whether point i is stable (NULL = all stable). The piece between points i and i+1 is drawn
 * stable (black, solid) when both ends are stable, unstable (grey, dashed) otherwise.
 * NaN in x or y is a gap. */
typedef struct plot_branch {
    const double *x;
    const double *y;
    const bool *stable; /* NULL = all stable */
    size_t n;
    const char *label;  /* written beside the branch's last point, e.g. "C#uP#d"; NULL = none */
} plot_branch;

typedef enum plot_event_kind {
    PLOT_EVENT_PITCHFORK = 0, /* drawn as a circle */
    PLOT_EVENT_SADDLE_NODE,   /* drawn as a square */
    PLOT_EVENT_OTHER          /* any other located event (a bifurcation not classified as
                                 either): drawn as a diamond */
} plot_event_kind;

typedef struct plot_event {
    double x, y; /* NaN in either: the event is skipped */
    plot_event_kind kind;
} plot_event;

/* plot_branches: axis labels are the caller's (PLplot text escapes allowed, e.g. "#gDW = dw/l"). */
typedef struct plot_branch_data {
    const char *title;   /* NULL ok */
    const char *x_label; /* NULL = "" */
    const char *y_label; /* NULL = "" */
    const plot_branch *branches;
    size_t n_branches;
    const plot_event *events;
    size_t n_events;
    int width_px, height_px; /* 0 = default */
} plot_branch_data;

void plot_branch_data_default(plot_branch_data *d);
plot_status plot_branches(const char *png_path, const plot_branch_data *d, char *why, size_t why_len);

/* Several continuation diagrams side by side on one width_px x height_px page (0 = default),
 * panel k in the k-th vertical slice, each drawn as plot_branches draws one (the panels' own
 * width_px / height_px are not used). ribbon-sim continue --plot: Delta Z and A against Delta W. */
#define PLOT_PANELS_MAX 4
plot_status plot_branches_panels(const char *png_path, const plot_branch_data *panels,
                                 size_t n_panels, int width_px, int height_px, char *why,
                                 size_t why_len);

/* plot_sweep: the regime map of a parameter sweep (ribbon-sim sweep --plot). Each classified
 * point is a marker: circle asymmetric (pitchfork first), square symmetric (saddle-node first),
 * triangle no snap, cross failed (PLOT_REGIME_UNKNOWN); a point where no stable state was found
 * is a grey diamond, with a grey bar up to where the state was last found. Located boundaries
 * are lines (dark grey, solid or dashed), optionally with small diamonds at their points. With
 * legend, a legend on the right names every kind of marker drawn and each line's text. Axes and
 * their meaning are the caller's: phi and Gamma for a phase diagram, Gamma and the first
 * instability's Delta W for one phi. */
typedef struct plot_sweep_point {
    double x, y;        /* NaN in either: the point is skipped */
    plot_regime regime;
    bool no_state;      /* no stable state found here: a grey diamond (regime ignored) */
    double bar_to;      /* with no_state: a grey bar from y to bar_to (NaN or y: none) */
    double bar_from;    /* with a bar: where it starts instead of y (0: at y), e.g. the two folds
                           that bound a gap without the state */
} plot_sweep_point;

typedef struct plot_sweep_line {
    const double *x, *y; /* n points in order; NaN is a gap */
    size_t n;
    bool dashed;         /* dashed (a boundary between other regimes) or solid */
    bool marked;         /* a small diamond at every point */
    const char *legend;  /* the legend's text for this kind of line (NULL: not in the legend) */
} plot_sweep_line;

typedef struct plot_sweep_data {
    const char *title;               /* NULL ok */
    const char *x_label, *y_label;   /* NULL = "" */
    double x0, x1, y0, y1;           /* the swept span; the axes pad it by 6% (x) and 8% (y) */
    const plot_sweep_point *points;
    size_t n_points;
    const plot_sweep_line *lines;
    size_t n_lines;
    int width_px, height_px;         /* 0 = default */
    bool legend;                     /* a legend on the right of the axes */
} plot_sweep_data;

/* Nothing to draw, span [0, 1] x [0, 1], default size. */
void plot_sweep_data_default(plot_sweep_data *d);
plot_status plot_sweep(const char *png_path, const plot_sweep_data *d, char *why, size_t why_len);

/* plot_boundary: curves of a two-parameter continuation (ribbon-sim boundary --plot): up to
 * PLOT_BOUNDARY_CURVES_MAX solid lines, one colour each and each named in the legend, optionally
 * with an open marker at each of its points (circle: a pitchfork curve, square: a saddle-node
 * curve); under them a sweep's classified points in grey with plot_sweep's markers (circle
 * asymmetric, square symmetric, cross otherwise); optionally one special point (a codimension-2
 * point) as a star on a dashed vertical line through it. The legend, inside at the upper left,
 * names every curve, each kind of point present, the special point, and a note line of text; the
 * y axis gets room for it above the data. Axes fit the finite data, padded by 6% (x), 8% (y). */
#define PLOT_BOUNDARY_CURVES_MAX 6

typedef enum plot_curve_mark {
    PLOT_CURVE_MARK_NONE = 0, /* a line only */
    PLOT_CURVE_MARK_CIRCLE,   /* an open circle at every point (pitchforks) */
    PLOT_CURVE_MARK_SQUARE    /* an open square at every point (saddle-nodes) */
} plot_curve_mark;

typedef struct plot_boundary_curve {
    const double *x, *y; /* n points in order; NaN is a gap */
    size_t n;
    plot_curve_mark mark;
    const char *label;   /* the legend's text; NULL = "" */
} plot_boundary_curve;

typedef struct plot_boundary_data {
    const char *title;             /* NULL ok */
    const char *x_label, *y_label; /* NULL = "" */
    const plot_boundary_curve *curves;
    size_t n_curves;               /* at most PLOT_BOUNDARY_CURVES_MAX */
    const plot_sweep_point *points; /* grey markers under the curves */
    size_t n_points;
    double star_x, star_y;         /* the special point; NaN = none */
    const char *star_label;        /* its legend text (the star and the dashed line); NULL = "" */
    const char *note;              /* a last legend line, text only; NULL = none */
    int width_px, height_px;       /* 0 = default */
} plot_boundary_data;

/* Nothing to draw, no special point (NaN), default size. */
void plot_boundary_data_default(plot_boundary_data *d);
plot_status plot_boundary(const char *png_path, const plot_boundary_data *d, char *why, size_t why_len);

#endif
