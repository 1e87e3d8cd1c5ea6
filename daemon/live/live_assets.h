/* live_assets.h: the live page's files as the API serves them (api_asset): the page itself,
 * embedded in ribbond at build time from daemon/live/web/, and Chart.js, read once at start-up
 * from Debian's libjs-chart.js under /usr/share/javascript (never a CDN, never a copy in the
 * repository). */
#ifndef RIBBON_DAEMON_LIVE_ASSETS_H
#define RIBBON_DAEMON_LIVE_ASSETS_H

#include <stddef.h>

#include "api.h"

#define LIVE_CHARTJS_FILE "/usr/share/javascript/chart.js/chart.min.js"
#define LIVE_CHARTJS_PATH "/javascript/chart.js/chart.min.js"

typedef struct live_assets {
    api_asset list[8];
    size_t n;
    unsigned char *chartjs;    /* malloc'ed file contents, NULL when missing */
    char paths[8][64];         /* storage for the list's paths */
    char warning[256];         /* "" or why Chart.js is missing (the page then says so) */
} live_assets;

/* Fills a: "/" (index.html), "/live.css", "/live.js" and, when the file is there, Chart.js. */
void live_assets_load(live_assets *a);
void live_assets_free(live_assets *a);

#endif
