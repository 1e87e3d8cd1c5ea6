/* live_assets.c: the page's files (see live_assets.h). */
#include "live_assets.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

typedef struct live_embedded {
    const char *name;
    const unsigned char *data;
    size_t len;
} live_embedded;
extern const live_embedded live_embedded_files[]; /* live_web_data.c, generated */

static const char *type_of(const char *name)
{
    const char *dot = strrchr(name, '.');
    if (dot && strcmp(dot, ".html") == 0) return "text/html; charset=utf-8";
    if (dot && strcmp(dot, ".css") == 0) return "text/css; charset=utf-8";
    if (dot && strcmp(dot, ".js") == 0) return "text/javascript; charset=utf-8";
    return "application/octet-stream";
}

void live_assets_load(live_assets *a)
{
    memset(a, 0, sizeof *a);
    for (const live_embedded *e = live_embedded_files; e->name && a->n < 7; e++) {
        api_asset *x = &a->list[a->n];
        if (strcmp(e->name, "index.html") == 0) x->path = "/";
        else {
            snprintf(a->paths[a->n], sizeof a->paths[a->n], "/%s", e->name);
            x->path = a->paths[a->n];
        }
        x->content_type = type_of(e->name);
        x->data = e->data;
        x->len = e->len;
        a->n++;
    }
    FILE *f = fopen(LIVE_CHARTJS_FILE, "rb");
    struct stat st;
    if (!f || fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size <= 0 || st.st_size > (64 << 20)) {
        snprintf(a->warning, sizeof a->warning, "%s is missing (%s): the live page has no plots; install libjs-chart.js",
                 LIVE_CHARTJS_FILE, f ? "not a regular file" : strerror(errno));
        if (f) fclose(f);
        return;
    }
    a->chartjs = malloc((size_t)st.st_size);
    if (!a->chartjs || fread(a->chartjs, 1, (size_t)st.st_size, f) != (size_t)st.st_size) {
        snprintf(a->warning, sizeof a->warning, "%s could not be read: the live page has no plots", LIVE_CHARTJS_FILE);
        free(a->chartjs);
        a->chartjs = NULL;
        fclose(f);
        return;
    }
    fclose(f);
    api_asset *x = &a->list[a->n++];
    x->path = LIVE_CHARTJS_PATH;
    x->content_type = "text/javascript; charset=utf-8";
    x->data = a->chartjs;
    x->len = (size_t)st.st_size;
}

void live_assets_free(live_assets *a)
{
    free(a->chartjs);
    a->chartjs = NULL;
    a->n = 0;
}
