/*
 * plot_style.c: the palette and text defaults of every figure (see plot_style.h).
 *
 * Colours follow the paper: stable black, unstable grey; asymmetric blue and symmetric red as in
 * its phase diagram; measured blue against predicted vermilion (a pair that stays apart for
 * colour-blind readers). The table is const: nothing here changes after start-up.
 */
#include "plot_style.h"

#include <plplot.h>

static const unsigned char plot_palette[PLOT_COL_COUNT][3] = {
    [PLOT_COL_BACKGROUND] = {255, 255, 255},
    [PLOT_COL_INK] = {0, 0, 0},
    [PLOT_COL_MEASURED] = {0, 90, 200},
    [PLOT_COL_PREDICTED] = {213, 94, 0},
    [PLOT_COL_UNSTABLE] = {150, 150, 150},
    [PLOT_COL_CELL_ASYM] = {198, 219, 239},
    [PLOT_COL_CELL_SYM] = {252, 208, 196},
    [PLOT_COL_CELL_NOSNAP] = {222, 222, 222},
    [PLOT_COL_CELL_UNKNOWN] = {250, 240, 190},
    [PLOT_COL_MARK_ASYM] = {8, 48, 140},
    [PLOT_COL_MARK_SYM] = {170, 20, 20},
    [PLOT_COL_MARK_OTHER] = {60, 60, 60},
    [PLOT_COL_GRID] = {225, 225, 225},
    /* Named curves, one colour each: the Okabe-Ito set, apart for colour-blind readers. */
    [PLOT_COL_SERIES_1] = {0, 114, 178},
    [PLOT_COL_SERIES_2] = {230, 159, 0},
    [PLOT_COL_SERIES_3] = {0, 158, 115},
    [PLOT_COL_SERIES_4] = {204, 121, 167},
    [PLOT_COL_SERIES_5] = {86, 180, 233},
    [PLOT_COL_SERIES_6] = {213, 94, 1}, /* one blue step off PLOT_COL_PREDICTED, so tests tell them apart */
    [PLOT_COL_CELL_NOUPPER] = {228, 212, 240},
    [PLOT_COL_CALIBRATED] = {0, 140, 100},
    [PLOT_COL_CALIBRATED_BAND] = {205, 235, 222},
};

void plot_style_rgb(enum plot_color c, int *r, int *g, int *b)
{
    if ((int)c < 0 || c >= PLOT_COL_COUNT)
        c = PLOT_COL_INK;
    *r = plot_palette[c][0];
    *g = plot_palette[c][1];
    *b = plot_palette[c][2];
}

void plot_style_palette(void)
{
    PLINT r[PLOT_COL_COUNT], g[PLOT_COL_COUNT], b[PLOT_COL_COUNT];
    for (int i = 0; i < PLOT_COL_COUNT; i++) {
        r[i] = plot_palette[i][0];
        g[i] = plot_palette[i][1];
        b[i] = plot_palette[i][2];
    }
    plscmap0(r, g, b, PLOT_COL_COUNT);
}

void plot_style_defaults(void)
{
    plfontld(1);      /* extended Hershey set, used only where unicode text is not */
    plschr(0.0, PLOT_CHAR_SCALE);
    plwidth(PLOT_WIDTH_THIN);
    plcol0(PLOT_COL_INK);
    pllsty(PLOT_LSTY_SOLID);
}
