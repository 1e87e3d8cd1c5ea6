/*
 * plot_session.h (private to the plot module): one PLplot figure, from an empty stream to a
 * verified PNG file. See plot_session.c for what PLplot does on errors and how it is contained.
 */
#ifndef RIBBON_PLOT_SESSION_H
#define RIBBON_PLOT_SESSION_H

#include "plot.h"

#include <stddef.h>

#define PLOT_DEVICE "pngcairo"

/* Draws one figure on the current PLplot stream (already initialised, palette set, page
 * begun). Returns PLOT_OK or an error with a reason; a PLplot abort during the call is caught by
 * the session afterwards. */
typedef plot_status (*plot_draw_fn)(void *ctx, char *why, size_t why_len);

/* Runs draw on a fresh PLplot stream of the given device writing a width_px x height_px page to
 * png_path (through a temporary file renamed on success). device is PLOT_DEVICE in production;
 * tests pass other names to exercise the missing-driver path. */
plot_status plot_session_run(const char *device, const char *png_path, int width_px, int height_px,
                             plot_draw_fn draw, void *ctx, char *why, size_t why_len);

/* Writes a reason into why (NUL-terminated, truncated to why_len; no-op when why is NULL or
 * why_len is 0) and returns st, so that error paths read `return plot_fail(st, why, n, ...)`. */
plot_status plot_fail(plot_status st, char *why, size_t why_len, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* Resolves 0 to the default and checks the range; name is "width" or "height" for the reason. */
plot_status plot_size_resolve(int requested, int def, const char *name, int *out, char *why, size_t why_len);

#endif
