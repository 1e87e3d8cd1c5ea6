/* sim_plot_continue.c: the continuation diagram of `ribbon-sim continue --plot` (see
 * sim_plot_continue.h), drawn by the plot module (plot_branches_panels, which also contains
 * PLplot's fatal errors). This file only turns a rod_analysis into plain arrays: two panels,
 * Delta Z and A against Delta W, one plot_branch per continuation branch (a switched branch
 * labelled "switched"), one plot_event per located event in each panel. */
#include "sim_plot_continue.h"

#include "plot.h"

#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#define PAGE_W 1400
#define PAGE_H 600

/* The arrays both panels draw from: x shared, y per panel. */
typedef struct branch_arrays {
    double *x, *dz, *a;
    bool *stable;
} branch_arrays;

int sim_plot_continue(const char *path, const rod_analysis *a, const char *title, char *why, size_t why_len)
{
    int nb = a->nbranches > 0 ? a->nbranches : 0, ne = a->nevents > 0 ? a->nevents : 0;
    branch_arrays *arr = calloc((size_t)nb + 1, sizeof *arr);
    plot_branch *bz = calloc((size_t)nb + 1, sizeof *bz), *ba = calloc((size_t)nb + 1, sizeof *ba);
    plot_event *ez = calloc((size_t)ne + 1, sizeof *ez), *ea = calloc((size_t)ne + 1, sizeof *ea);
    int ok = arr && bz && ba && ez && ea;
    for (int b = 0; ok && b < nb; b++) {
        const rod_branch *br = &a->branches[b];
        size_t n = br->n;
        arr[b].x = malloc((n + 1) * sizeof(double));
        arr[b].dz = malloc((n + 1) * sizeof(double));
        arr[b].a = malloc((n + 1) * sizeof(double));
        arr[b].stable = malloc((n + 1) * sizeof(bool));
        ok = arr[b].x && arr[b].dz && arr[b].a && arr[b].stable;
        for (size_t i = 0; ok && i < n; i++) {
            arr[b].x[i] = br->points[i].dw;
            arr[b].dz[i] = br->points[i].dz;
            arr[b].a[i] = br->points[i].a;
            arr[b].stable[i] = br->points[i].stable;
        }
        const char *label = br->parent_event >= 0 ? "switched" : NULL;
        bz[b] = (plot_branch){arr[b].x, arr[b].dz, arr[b].stable, n, label};
        ba[b] = (plot_branch){arr[b].x, arr[b].a, arr[b].stable, n, label};
    }
    for (int e = 0; ok && e < ne; e++) {
        const rod_event *ev = &a->events[e];
        plot_event_kind k = ev->kind == ROD_EVENT_PITCHFORK     ? PLOT_EVENT_PITCHFORK
                            : ev->kind == ROD_EVENT_SADDLE_NODE ? PLOT_EVENT_SADDLE_NODE
                                                                : PLOT_EVENT_OTHER;
        ez[e] = (plot_event){ev->at.dw, ev->at.dz, k};
        ea[e] = (plot_event){ev->at.dw, ev->at.a, k};
    }
    int rc = -1;
    if (!ok) {
        snprintf(why, why_len, "out of memory drawing %s", path);
    } else {
        plot_branch_data panels[2];
        panels[0] = (plot_branch_data){.title = title ? title : "midpoint height",
                                       .x_label = "#gDW",
                                       .y_label = "#gDZ",
                                       .branches = bz,
                                       .n_branches = (size_t)nb,
                                       .events = ez,
                                       .n_events = (size_t)ne};
        panels[1] = (plot_branch_data){.title = "asymmetry A",
                                       .x_label = "#gDW",
                                       .y_label = "A (rad)",
                                       .branches = ba,
                                       .n_branches = (size_t)nb,
                                       .events = ea,
                                       .n_events = (size_t)ne};
        if (plot_branches_panels(path, panels, 2, PAGE_W, PAGE_H, why, why_len) == PLOT_OK)
            rc = 0;
    }
    for (int b = 0; arr && b < nb; b++) {
        free(arr[b].x);
        free(arr[b].dz);
        free(arr[b].a);
        free(arr[b].stable);
    }
    free(arr);
    free(bz);
    free(ba);
    free(ez);
    free(ea);
    return rc;
}
