/*
 * plot_legend.c: legends for the plot module (see plot_legend.h).
 *
 * pllegend takes one array per attribute; a figure describes its legend as a list of entries
 * instead and this file transposes it. Legends get a white background and a thin black frame so
 * that they stay readable where they overlap shaded cells.
 */
#include "plot_legend.h"

#include "plot_style.h"

#include <plplot.h>

void plot_legend_draw(const plot_legend_entry *e, int n, int position, double x, double y)
{
    if (n <= 0)
        return;
    if (n > PLOT_LEGEND_MAX)
        n = PLOT_LEGEND_MAX;

    PLINT opt[PLOT_LEGEND_MAX], text_col[PLOT_LEGEND_MAX], box_col[PLOT_LEGEND_MAX], box_pat[PLOT_LEGEND_MAX];
    PLINT line_col[PLOT_LEGEND_MAX], line_sty[PLOT_LEGEND_MAX], sym_col[PLOT_LEGEND_MAX], sym_num[PLOT_LEGEND_MAX];
    PLFLT box_scale[PLOT_LEGEND_MAX], box_lw[PLOT_LEGEND_MAX], line_w[PLOT_LEGEND_MAX], sym_scale[PLOT_LEGEND_MAX];
    const char *text[PLOT_LEGEND_MAX], *sym[PLOT_LEGEND_MAX];

    for (int i = 0; i < n; i++) {
        switch (e[i].kind) {
        case PLOT_LEGEND_KIND_LINE: opt[i] = PL_LEGEND_LINE; break;
        case PLOT_LEGEND_KIND_SYMBOL: opt[i] = PL_LEGEND_SYMBOL; break;
        case PLOT_LEGEND_KIND_LINE_SYMBOL: opt[i] = PL_LEGEND_LINE | PL_LEGEND_SYMBOL; break;
        case PLOT_LEGEND_KIND_BOX: opt[i] = PL_LEGEND_COLOR_BOX; break;
        case PLOT_LEGEND_KIND_NONE:
        default: opt[i] = PL_LEGEND_NONE; break;
        }
        text[i] = e[i].text ? e[i].text : "";
        text_col[i] = PLOT_COL_INK;
        box_col[i] = e[i].color;
        box_pat[i] = 0; /* solid fill */
        box_scale[i] = 0.8;
        box_lw[i] = 1.0;
        line_col[i] = e[i].color;
        line_sty[i] = e[i].line_style > 0 ? e[i].line_style : PLOT_LSTY_SOLID;
        line_w[i] = e[i].line_width > 0 ? e[i].line_width : PLOT_WIDTH_DATA;
        sym_col[i] = e[i].color;
        sym_scale[i] = e[i].symbol_scale > 0 ? e[i].symbol_scale : 1.0;
        sym_num[i] = e[i].kind == PLOT_LEGEND_KIND_LINE_SYMBOL ? 2 : 1;
        sym[i] = e[i].symbol ? e[i].symbol : PLOT_GLYPH_DOT;
    }

    PLFLT w = 0.0, h = 0.0;
    pllsty(PLOT_LSTY_SOLID);
    plwidth(PLOT_WIDTH_THIN);
    pllegend(&w, &h, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX, position, x, y, 0.06,
             PLOT_COL_BACKGROUND, PLOT_COL_INK, PLOT_LSTY_SOLID, 0, 0, n, opt, 0.8, 0.8, 2.0, 0.0, text_col, text,
             box_col, box_pat, box_scale, box_lw, line_col, line_sty, line_w, sym_col, sym_scale, sym_num, sym);
    pllsty(PLOT_LSTY_SOLID);
    plwidth(PLOT_WIDTH_THIN);
    plcol0(PLOT_COL_INK);
}
