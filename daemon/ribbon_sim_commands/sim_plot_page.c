/* sim_plot_page.c: the page and marker helpers of ribbon-sim's figures (see sim_plot_page.h).
 * PLplot keeps its streams in globals; open makes a fresh stream and close ends it with plend1,
 * so a figure leaves nothing behind. The pngcairo driver reports no write errors, hence the file
 * is probed before (can it be opened for writing?) and measured after. */
#include "sim_plot_page.h"

#include <math.h>
#include <plplot.h>
#include <stdio.h>

int sim_plot_page_open(const char *path, int width_px, int height_px, char *err, size_t errlen)
{
    FILE *probe = fopen(path, "wb");
    if (!probe) {
        snprintf(err, errlen, "cannot write %s", path);
        return -1;
    }
    fclose(probe);
    PLINT stream;
    plmkstrm(&stream);
    plsdev("pngcairo");
    plsfnam(path);
    plspage(0, 0, width_px, height_px, 0, 0);
    return 0;
}

int sim_plot_page_close(const char *path)
{
    plend1();
    FILE *check = fopen(path, "rb");
    long size = 0;
    if (check) {
        fseek(check, 0, SEEK_END);
        size = ftell(check);
        fclose(check);
    }
    return size > 0;
}

void sim_plot_polygon(double x, double y, double rx, double ry, int n_sides, double rot)
{
    PLFLT px[65], py[65];
    if (n_sides < 3 || n_sides > 64)
        return;
    for (int k = 0; k <= n_sides; k++) {
        double t = rot + 2.0 * M_PI * k / n_sides;
        px[k] = x + rx * cos(t);
        py[k] = y + ry * sin(t);
    }
    plline(n_sides + 1, px, py);
}
