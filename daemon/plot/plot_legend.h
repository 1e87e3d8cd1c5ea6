/*
 * plot_legend.h (private to the plot module): a legend from a short list of entries, drawn
 * with PLplot's pllegend (whose twenty parallel arrays are filled here, once).
 */
#ifndef RIBBON_PLOT_LEGEND_H
#define RIBBON_PLOT_LEGEND_H

#define PLOT_LEGEND_MAX 12

typedef enum plot_legend_kind {
    PLOT_LEGEND_KIND_LINE,        /* a line sample */
    PLOT_LEGEND_KIND_SYMBOL,      /* a marker */
    PLOT_LEGEND_KIND_LINE_SYMBOL, /* a line with markers on it */
    PLOT_LEGEND_KIND_BOX,         /* a filled colour box (shaded regions) */
    PLOT_LEGEND_KIND_NONE         /* text only */
} plot_legend_kind;

typedef struct plot_legend_entry {
    const char *text;
    plot_legend_kind kind;
    int color;          /* cmap0 index of the line, marker or box */
    int line_style;     /* pllsty style of the line sample */
    double line_width;
    const char *symbol; /* UTF-8 glyph for markers */
    double symbol_scale;
} plot_legend_entry;

/* Draws up to PLOT_LEGEND_MAX entries; position is PLplot's PL_POSITION_* flags relative to the
 * current viewport, x/y the offsets in normalised viewport units. */
void plot_legend_draw(const plot_legend_entry *e, int n, int position, double x, double y);

#endif
