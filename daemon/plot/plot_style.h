/*
 * plot_style.h (private to the plot module): the house style of every figure, one place.
 *
 * PLplot colours are indices into the stream's cmap0; plot_style_palette() loads this table
 * into the current stream (before plinit, so that index 0 is the page background). The RGB
 * values are exact so tests can count a series' pixels in the PNG.
 */
#ifndef RIBBON_PLOT_STYLE_H
#define RIBBON_PLOT_STYLE_H

enum plot_color {
    PLOT_COL_BACKGROUND = 0, /* white page */
    PLOT_COL_INK,            /* black: axes, text, stable branches, boundary */
    PLOT_COL_MEASURED,       /* blue: measured curve and snap */
    PLOT_COL_PREDICTED,      /* vermilion: predicted curve and snap */
    PLOT_COL_UNSTABLE,       /* grey: unstable branches */
    PLOT_COL_CELL_ASYM,      /* pale blue: predicted asymmetric cells */
    PLOT_COL_CELL_SYM,       /* pale red: predicted symmetric cells */
    PLOT_COL_CELL_NOSNAP,    /* pale grey: predicted no-snap cells */
    PLOT_COL_CELL_UNKNOWN,   /* pale yellow: failed / unclassified cells */
    PLOT_COL_MARK_ASYM,      /* dark blue: measured asymmetric trials */
    PLOT_COL_MARK_SYM,       /* dark red: measured symmetric trials */
    PLOT_COL_MARK_OTHER,     /* dark grey: no-snap and unknown trials */
    PLOT_COL_GRID,           /* light grey: grid lines */
    PLOT_COL_SERIES_1,       /* blue: first of the named curves (plot_boundary) */
    PLOT_COL_SERIES_2,       /* orange */
    PLOT_COL_SERIES_3,       /* bluish green */
    PLOT_COL_SERIES_4,       /* reddish purple */
    PLOT_COL_SERIES_5,       /* sky blue */
    PLOT_COL_SERIES_6,       /* vermilion */
    PLOT_COL_CELL_NOUPPER,   /* pale lilac: predicted cells without a stable upper state */
    PLOT_COL_CALIBRATED,     /* bluish green: the calibrated prediction's snap (issue 32 B) */
    PLOT_COL_CALIBRATED_BAND, /* pale green: its 1-sigma band */
    PLOT_COL_COUNT
};

/* RGB of each index (0-255), for tests that look for a colour in the PNG. */
void plot_style_rgb(enum plot_color c, int *r, int *g, int *b);

/* Loads the palette into the current stream; call before plinit. */
void plot_style_palette(void);
/* Character height, font and line width defaults; call after plinit. */
void plot_style_defaults(void);

/* Character height: PLplot's default scaled by this (plschr(0, PLOT_CHAR_SCALE)). */
#define PLOT_CHAR_SCALE 1.0

/* Line widths (PLplot width units: about a pixel on the cairo devices at 1200 px). */
#define PLOT_WIDTH_DATA 3.0
#define PLOT_WIDTH_THIN 1.0
/* PLplot line styles (pllsty): 1 solid, 2 short dashes, 3 long dashes, 4 long dash short gap. */
#define PLOT_LSTY_SOLID 1
#define PLOT_LSTY_DASHED 3
#define PLOT_LSTY_DOTTED 2

/* Marker glyphs (UTF-8, drawn with plstring and shown in pllegend; DejaVu has them all). */
#define PLOT_GLYPH_DOT "•"
#define PLOT_GLYPH_CIRCLE_OPEN "○"
#define PLOT_GLYPH_SQUARE_FILLED "■"
#define PLOT_GLYPH_SQUARE_OPEN "□"
#define PLOT_GLYPH_CROSS "×"
#define PLOT_GLYPH_DIAMOND_OPEN "◇"
#define PLOT_GLYPH_TRIANGLE_DOWN "▼"
#define PLOT_GLYPH_STAR "★"

#endif
