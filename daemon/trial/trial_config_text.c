/* trial_config_text.c: the configuration a trial ran with, as text kept in its row: the rig file
 * and the scene file as they were (each capped at 1 MiB), and the operator's note; and the scene
 * file's part of such a text found again. */
#include "trial_config_text.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Appends the file's text (or a note that it could not be read) to a growing buffer. */
static int append_file(char **buf, size_t *len, size_t *cap, const char *label, const char *path)
{
    FILE *f = fopen(path, "rb");
    char head[1200];
    int hn = snprintf(head, sizeof head, "# %s %s\n", label, path);
    size_t need = (size_t)hn + 1;
    long size = 0;
    if (f && fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    if (size < 0 || size > (1 << 20)) size = 0;
    if (f) rewind(f);
    need += (size_t)size + 64;
    if (*len + need > *cap) {
        size_t nc = (*len + need) * 2;
        char *nb = realloc(*buf, nc);
        if (!nb) {
            if (f) fclose(f);
            return -1;
        }
        *buf = nb;
        *cap = nc;
    }
    memcpy(*buf + *len, head, (size_t)hn);
    *len += (size_t)hn;
    if (!f) {
        *len += (size_t)snprintf(*buf + *len, 64, "# (could not be read)\n");
    } else {
        *len += fread(*buf + *len, 1, (size_t)size, f);
        fclose(f);
        if (*len > 0 && (*buf)[*len - 1] != '\n') (*buf)[(*len)++] = '\n';
    }
    (*buf)[*len] = '\0';
    return 0;
}

char *trial_config_text(const rig_config *cfg, const char *note)
{
    char *buf = NULL;
    size_t len = 0, cap = 0;
    if (append_file(&buf, &len, &cap, "rig file", cfg->path) ||
        append_file(&buf, &len, &cap, "scene file", cfg->scene_path)) {
        free(buf);
        return NULL;
    }
    if (note && *note) {
        size_t n = strlen(note) + 16;
        char *nb = realloc(buf, len + n + 1);
        if (!nb) {
            free(buf);
            return NULL;
        }
        buf = nb;
        snprintf(buf + len, n + 1, "# note: %s\n", note);
    }
    return buf;
}

/* The start of the last line of text[0, end) that begins with prefix, or NULL. */
static const char *last_line_with(const char *text, const char *end, const char *prefix)
{
    size_t n = strlen(prefix);
    const char *found = NULL;
    for (const char *p = text; p && p < end; p = strchr(p, '\n'), p = p ? p + 1 : NULL)
        if ((size_t)(end - p) >= n && !strncmp(p, prefix, n)) found = p;
    return found;
}

int trial_config_text_scene(const char *text, const char **begin, size_t *len)
{
    const char *end = text + strlen(text);
    const char *head = last_line_with(text, end, "# scene file ");
    if (!head) return -1;
    const char *body = strchr(head, '\n');
    if (!body) return -1;
    body++;
    if (!strncmp(body, "# (could not be read)", 21)) return -1;
    /* What trial_config_text and a replay's row append after the scene: at most these two. */
    const char *tail = last_line_with(body, end, "# replay of trial ");
    if (tail) end = tail;
    tail = last_line_with(body, end, "# note: ");
    if (tail) end = tail;
    *begin = body;
    *len = (size_t)(end - body);
    return 0;
}
