/* scene_write.c: a scene written from the loader's key table (scene_write.h). */
#include "scene_write.h"

#include "scene_file.h"

#include <math.h>
#include <string.h>

int cfg_scene_write(FILE *f, const rod_scene *sc, const char *header)
{
    size_t n = 0;
    const cfg_scene_key *keys = cfg_scene_keys(&n);
    const char *section = NULL;
    if (header) {
        const char *p = header;
        while (*p) {
            const char *e = strchr(p, '\n');
            size_t len = e ? (size_t)(e - p) : strlen(p);
            fprintf(f, "; %.*s\n", (int)len, p);
            p += len + (e ? 1 : 0);
        }
    }
    for (size_t i = 0; i < n; i++) {
        const cfg_scene_key *k = &keys[i];
        const char *base = (const char *)sc + k->offset;
        if (!section || strcmp(section, k->section)) {
            fprintf(f, "%s[%s]\n", section ? "\n" : "", k->section);
            section = k->section;
        }
        /* the loader refuses a stiffness factor beside compliant hinges (it means rigid creases) */
        if (!strcmp(k->section, "folds") && !strcmp(k->name, "stiffness_factor") && !rod_scene_hinge_rigid(sc))
            continue;
        switch (k->type) {
        case CFG_TYPE_DOUBLE: {
            double v;
            memcpy(&v, base, sizeof v);
            if (isnan(v)) continue;
            fprintf(f, "%s = %.17g\n", k->name, v);
            break;
        }
        case CFG_TYPE_DOUBLE_OR_WORD: {
            double v;
            memcpy(&v, base, sizeof v);
            if (isinf(v)) fprintf(f, "%s = %s\n", k->name, k->names[0]);
            else fprintf(f, "%s = %.17g\n", k->name, v);
            break;
        }
        case CFG_TYPE_INT: {
            int v;
            memcpy(&v, base, sizeof v);
            fprintf(f, "%s = %d\n", k->name, v);
            break;
        }
        case CFG_TYPE_VEC3: {
            double v[3];
            memcpy(v, base, sizeof v);
            fprintf(f, "%s = %.17g %.17g %.17g\n", k->name, v[0], v[1], v[2]);
            break;
        }
        case CFG_TYPE_ENUM: {
            int v;
            memcpy(&v, base, sizeof v);
            fprintf(f, "%s = %s\n", k->name, k->names[v]);
            break;
        }
        }
    }
    return ferror(f) ? -1 : 0;
}
