/* check_includes.c: the house's include rules, checked on the source tree (issue 12, DESIGN.md
 * section 2). Usage: check_includes SOURCE_ROOT. Prints every breach and exits 1 if there is one.
 *
 * What it reads: every .c/.h in config/, drivers/ (not its fuzz/ harnesses), daemon/ (all its
 * rooms) and vision/ (all its rooms, .cpp/.hpp too), and the files of sim/ so their includes can
 * be placed too (sim/ is checked for the floor rule only). Only quoted includes count ("x.h");
 * system headers are not the house's. A header is found by its file name (the build puts every
 * folder on the include path), so two headers of one name are themselves a breach.
 *
 * The rules:
 *  1. Floors. Every file is in a room: sim, drivers, vision (floor 0, none above another), config
 *     (floor 1: it fills the drivers' and the simulator's parameter structs), then daemon's
 *     rooms cli, store, plot, api, twin, trial, report (floors 2..8, in that order), the command
 *     rooms ribbonctl_commands and ribbon_sim_commands (9), and daemon/ itself, the programs'
 *     mains and rig_daemon (10). A file may include a header of its own room or of a room on a
 *     lower floor, never one of its own floor's other rooms or of a floor above. vision/'s rooms
 *     share floor 0 and stand on steps inside it (core 0.0, render 0.1, video, calib and source
 *     0.2, track 0.3, vision/ itself with vision.h 0.4): a vision room may include a room of
 *     vision/ on a lower step, and nothing of sim/ or drivers/, as before.
 *  2. Faces. A room with a face (the table below) is entered from outside only through it: a
 *     file of another room includes only the face's headers. A vision room's C++ face (.hpp: its
 *     C++ interface for the rooms above it in vision/) is entered from vision/ only.
 *  3. Ownership. A header belongs to the file it is named after: every function it declares is
 *     defined in that file (x.h -> x.c). A face, or a header without a file of its name, may
 *     declare functions of any file of its room, and of no other room.
 *  4. No loops. Files group into units: x.c with its own x.h (a face is a unit of its own). A
 *     unit that includes another's header depends on it; no chain of dependencies comes back to
 *     where it started (two files that include each other's headers are the shortest loop).
 *
 * The parsing is deliberately plain (this is a lint, not a compiler): comments and preprocessor
 * lines are dropped, a declaration is a top-level statement ending in ';' with a '(' and not a
 * typedef, and a definition is a line starting in column 0 with the name followed by '('. An
 * `extern "C" {` block is transparent (its declarations are top level: vision's C faces); a C++
 * namespace is not, so rule 3 judges the C declarations of vision/ and not its C++ internals. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

enum { MAX_FILES = 2048, MAX_INCLUDES = 64, NAME_LEN = 128, PATH_LEN = 512 };

typedef struct room {
    const char *name;   /* "drivers", "daemon/store", "daemon" (the programs) */
    int floor;
    int step;           /* order of the rooms of one folder on one floor (vision/'s), else 0 */
    const char *face[4]; /* the headers other rooms may include; {NULL}: every header is open */
} room;

/* The layering. A face is the header named after its room (daemon/store/store.h), which
 * includes the room's member headers others need; the command rooms' faces are the tables of
 * their commands. Rooms with {NULL} have no face: all their headers are open to the rooms above
 * (the floors still hold); drivers/ and config/ are families of members, each with its own
 * header (rule 3). A face in this table that is missing from the tree is a breach.
 * vision/'s rooms are C++ inside and C outside: each has one C face (vis_<room>.h, which vision.h
 * gathers for the house above); a room whose C++ another vision room builds on lists those .hpp
 * headers after it (core's glue and image-header check, source's interface). */
static const room rooms[] = {
    {"sim", 0, 0, {NULL}},
    {"drivers", 0, 0, {NULL}},
    {"vision/core", 0, 0, {"vis_core.h", "vis_internal.hpp", "image_header.hpp", NULL}},
    {"vision/render", 0, 1, {"vis_render.h", NULL}},
    {"vision/video", 0, 2, {"vis_video.h", NULL}},
    {"vision/calib", 0, 2, {"vis_calib.h", NULL}},
    {"vision/source", 0, 2, {"vis_source.h", "source.hpp", NULL}},
    {"vision/track", 0, 3, {"vis_track.h", NULL}},
    {"vision", 0, 4, {"vision.h", NULL}},
    {"config", 1, 0, {NULL}},
    {"daemon/cli", 2, 0, {"cli.h", NULL}},
    {"daemon/store", 3, 0, {"store.h", NULL}},
    {"daemon/plot", 4, 0, {"plot.h", NULL}},
    {"daemon/api", 5, 0, {"api.h", NULL}},
    {"daemon/live", 6, 0, {"live.h", NULL}},
    {"daemon/twin", 6, 0, {"twin.h", NULL}},
    {"daemon/trial", 7, 0, {"trial.h", NULL}},
    {"daemon/rigsim", 7, 0, {"rigsim.h", NULL}},
    {"daemon/family", 7, 0, {"family.h", NULL}},
    {"daemon/report", 8, 0, {"trial_report.h", NULL}},
    {"daemon/campaign", 8, 0, {"campaign.h", NULL}},
    {"daemon/check", 8, 0, {"check.h", NULL}},
    {"daemon/ribbonctl_commands", 9, 0, {"ctl.h", NULL}},
    {"daemon/ribbon_sim_commands", 9, 0, {"sim_cmd.h", NULL}},
    {"daemon", 10, 0, {NULL}},
};
enum { N_ROOMS = sizeof rooms / sizeof rooms[0] };

typedef struct file {
    char path[PATH_LEN];  /* relative to the root, "drivers/rail.c" */
    char name[NAME_LEN];  /* "rail.c" */
    char stem[NAME_LEN];  /* "rail" */
    int is_header;
    int checked;          /* 2: every rule; 1: the floors only (sim/) */
    int room;             /* index into rooms */
    int unit;             /* index of the unit it belongs to */
    int n_inc;
    int inc[MAX_INCLUDES]; /* resolved included files (indices) */
    int inc_line[MAX_INCLUDES];
    char *text;           /* comments removed, lines kept */
} file;

static file files[MAX_FILES];
static int n_files;
static int breaches;

static void breach(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static void breach(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    putchar('\n');
    breaches++;
}

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

static int room_of(const char *rel)
{
    int best = -1;
    size_t best_len = 0;
    for (int i = 0; i < N_ROOMS; i++) {
        size_t n = strlen(rooms[i].name);
        if (strncmp(rel, rooms[i].name, n) == 0 && rel[n] == '/' && n > best_len) {
            /* "daemon" and "vision" hold only the files at their top; a deeper folder is a room
             * of its own. */
            if ((strcmp(rooms[i].name, "daemon") == 0 || strcmp(rooms[i].name, "vision") == 0) &&
                strchr(rel + n + 1, '/'))
                continue;
            best = i;
            best_len = n;
        }
    }
    return best;
}

static int is_face(const file *f)
{
    const room *r = &rooms[f->room];
    for (int i = 0; i < 4 && r->face[i]; i++)
        if (strcmp(r->face[i], f->name) == 0)
            return 1;
    return 0;
}

static int has_face(int room_index)
{
    return rooms[room_index].face[0] != NULL;
}

/* Whether two rooms are in one top folder ("vision/core" and "vision"). */
static int same_folder(const room *a, const room *b)
{
    size_t na = strcspn(a->name, "/"), nb = strcspn(b->name, "/");
    return na == nb && strncmp(a->name, b->name, na) == 0;
}

/* Whether room `from` may include a header of room `to` (rule 1). */
static int below(const room *to, const room *from)
{
    if (to->floor != from->floor)
        return to->floor < from->floor;
    return same_folder(to, from) && to->step < from->step;
}

/* "3", or "0.2" for a room on a step of its floor. */
static const char *floor_name(const room *r, char *buf, size_t len)
{
    if (r->step)
        snprintf(buf, len, "%d.%d", r->floor, r->step);
    else
        snprintf(buf, len, "%d", r->floor);
    return buf;
}

/* The file's text with comments and string/char literals blanked, newlines kept. */
static char *read_stripped(const char *path)
{
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return NULL;
    size_t cap = 4096, n = 0;
    char *s = malloc(cap);
    int c;
    while (s && (c = fgetc(fp)) != EOF) {
        if (n + 2 >= cap) {
            char *t = realloc(s, cap * 2);
            if (!t) {
                free(s);
                s = NULL;
                break;
            }
            s = t;
            cap *= 2;
        }
        s[n++] = (char)c;
    }
    fclose(fp);
    if (!s)
        return NULL;
    s[n] = '\0';
    /* Blank comments (keep newlines so line numbers stay). Include names are in quotes, so
     * string literals are left as they are. */
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '"') { /* skip a string literal */
            for (i++; i < n && s[i] != '"' && s[i] != '\n'; i++)
                if (s[i] == '\\' && i + 1 < n)
                    i++;
        } else if (s[i] == '\'') {
            for (i++; i < n && s[i] != '\'' && s[i] != '\n'; i++)
                if (s[i] == '\\' && i + 1 < n)
                    i++;
        } else if (s[i] == '/' && i + 1 < n && s[i + 1] == '*') {
            size_t j = i;
            for (; j < n && !(s[j] == '*' && j + 1 < n && s[j + 1] == '/'); j++)
                if (s[j] != '\n')
                    s[j] = ' ';
            if (j < n)
                s[j] = s[j + 1] = ' ';
            i = j + 1;
        } else if (s[i] == '/' && i + 1 < n && s[i + 1] == '/') {
            for (; i < n && s[i] != '\n'; i++)
                s[i] = ' ';
        }
    }
    return s;
}

static void add_file(const char *rel, const char *abs, int checked)
{
    if (n_files >= MAX_FILES) {
        breach("too many files (more than %d): raise MAX_FILES", MAX_FILES);
        return;
    }
    file *f = &files[n_files];
    memset(f, 0, sizeof *f);
    snprintf(f->path, sizeof f->path, "%s", rel);
    const char *slash = strrchr(rel, '/');
    const char *base = slash ? slash + 1 : rel;
    size_t bl = strlen(base);
    if (bl >= NAME_LEN) {
        breach("%s: file name too long", rel);
        return;
    }
    memcpy(f->name, base, bl + 1);
    memcpy(f->stem, base, bl + 1);
    char *dot = strrchr(f->stem, '.');
    if (dot)
        *dot = '\0';
    f->is_header = ends_with(rel, ".h") || ends_with(rel, ".hpp");
    f->checked = checked;
    f->room = room_of(rel);
    f->text = read_stripped(abs);
    if (!f->text) {
        breach("%s: cannot read", rel);
        return;
    }
    if (f->room < 0) {
        breach("%s: in no room of the layering (add its folder to check_includes.c)", rel);
        return;
    }
    n_files++;
}

static int wanted(const char *name)
{
    return ends_with(name, ".c") || ends_with(name, ".h") || ends_with(name, ".cpp") ||
           ends_with(name, ".hpp");
}

/* Walk root/rel; recurse unless flat. */
static void scan(const char *root, const char *rel, int checked, int flat)
{
    char abs[PATH_LEN];
    snprintf(abs, sizeof abs, "%s/%s", root, rel);
    DIR *d = opendir(abs);
    if (!d) {
        breach("%s: cannot open the folder", rel);
        return;
    }
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char r2[PATH_LEN], a2[PATH_LEN + NAME_LEN];
        snprintf(r2, sizeof r2, "%s/%s", rel, e->d_name);
        snprintf(a2, sizeof a2, "%s/%s", root, r2);
        struct stat st;
        if (stat(a2, &st) != 0)
            continue;
        if (S_ISDIR(st.st_mode)) {
            if (!flat)
                scan(root, r2, checked, flat);
        } else if (wanted(e->d_name)) {
            add_file(r2, a2, checked);
        }
    }
    closedir(d);
}

static int find_header(const char *name)
{
    int found = -1;
    for (int i = 0; i < n_files; i++)
        if (files[i].is_header && strcmp(files[i].name, name) == 0) {
            if (found >= 0) {
                breach("two headers named %s: %s and %s (an include of it is ambiguous)", name,
                       files[found].path, files[i].path);
                return found;
            }
            found = i;
        }
    return found;
}

static int line_of(const char *text, const char *p)
{
    int line = 1;
    for (const char *q = text; q < p; q++)
        line += *q == '\n';
    return line;
}

/* Collect each file's quoted includes that name a scanned header. */
static void read_includes(void)
{
    for (int i = 0; i < n_files; i++) {
        file *f = &files[i];
        for (const char *p = f->text; *p;) {
            const char *q = p;
            while (*q == ' ' || *q == '\t')
                q++;
            if (*q == '#') {
                q++;
                while (*q == ' ' || *q == '\t')
                    q++;
                if (strncmp(q, "include", 7) == 0) {
                    q += 7;
                    while (*q == ' ' || *q == '\t')
                        q++;
                    if (*q == '"') {
                        char name[NAME_LEN];
                        size_t k = 0;
                        for (q++; *q && *q != '"' && *q != '\n' && k + 1 < sizeof name; q++)
                            name[k++] = *q;
                        name[k] = '\0';
                        const char *base = strrchr(name, '/');
                        int h = find_header(base ? base + 1 : name);
                        if (h >= 0 && h != i && f->n_inc < MAX_INCLUDES) {
                            f->inc_line[f->n_inc] = line_of(f->text, p);
                            f->inc[f->n_inc++] = h;
                        }
                    }
                }
            }
            const char *nl = strchr(p, '\n');
            p = nl ? nl + 1 : p + strlen(p);
        }
    }
}

/* Rules 1 and 2. */
static void check_floors_and_faces(void)
{
    for (int i = 0; i < n_files; i++) {
        const file *f = &files[i];
        if (!f->checked)
            continue;
        for (int k = 0; k < f->n_inc; k++) {
            const file *h = &files[f->inc[k]];
            if (h->room == f->room)
                continue;
            const room *from = &rooms[f->room], *to = &rooms[h->room];
            char ff[16], ft[16];
            if (!below(to, from))
                breach("%s:%d: includes %s: %s (floor %s) may not include %s (floor %s)", f->path,
                       f->inc_line[k], h->path, from->name, floor_name(from, ff, sizeof ff),
                       to->name, floor_name(to, ft, sizeof ft));
            else if (has_face(h->room) && !is_face(h))
                breach("%s:%d: includes %s, a private header of %s (its face: %s)", f->path,
                       f->inc_line[k], h->path, to->name, to->face[0]);
            else if (ends_with(h->name, ".hpp") && !same_folder(from, to))
                breach("%s:%d: includes %s, C++ inside %s (its face: %s)", f->path,
                       f->inc_line[k], h->path, to->name, to->face[0]);
        }
    }
}

static int is_ident(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

/* Whether text defines `name`: a line starting in column 0 with the name followed by '('. */
static int defines(const char *text, const char *name)
{
    size_t n = strlen(name);
    for (const char *line = text; *line;) {
        const char *nl = strchr(line, '\n');
        size_t len = nl ? (size_t)(nl - line) : strlen(line);
        if (len && line[0] != ' ' && line[0] != '\t' && line[0] != '#' && line[0] != '}') {
            for (const char *p = line; p + n <= line + len; p++) {
                if (strncmp(p, name, n) != 0 || (p > line && is_ident(p[-1])) || is_ident(p[n]))
                    continue;
                const char *q = p + n;
                while (*q == ' ')
                    q++;
                if (*q == '(') {
                    /* A prototype ends in ';' before any '{'; a definition does not. */
                    const char *end = q;
                    while (*end && *end != ';' && *end != '{')
                        end++;
                    if (*end == '{')
                        return 1;
                }
            }
        }
        line = nl ? nl + 1 : line + len;
    }
    return 0;
}

/* Call fn(name) for every function the header declares. */
static void declared_functions(const file *h, void (*fn)(const file *, const char *, int),
                               int line_hint)
{
    (void)line_hint;
    const char *t = h->text;
    char stmt[4096];
    size_t sl = 0;
    int depth = 0, skipping = 0; /* skipping: the statement hit a '{' at depth 0 */
    int open_extern = 0;         /* extern "C" { blocks open at depth 0 (transparent) */
    int stmt_line = 1, line = 1;
    for (const char *p = t; *p; p++) {
        if (*p == '\n')
            line++;
        /* Preprocessor lines (with continuations) are not declarations. */
        if (*p == '#' && (p == t || p[-1] == '\n' || p[-1] == ' ' || p[-1] == '\t')) {
            const char *b = p;
            while (b > t && (b[-1] == ' ' || b[-1] == '\t'))
                b--;
            if (b == t || b[-1] == '\n') {
                while (*p && !(*p == '\n' && p[-1] != '\\'))
                    p++;
                if (!*p)
                    break;
                line++;
                continue;
            }
        }
        if (*p == '{') {
            if (depth == 0 && !skipping) {
                stmt[sl] = '\0';
                const char *s = stmt;
                while (*s == ' ' || *s == '\t' || *s == '\n')
                    s++;
                size_t n = strlen(s);
                while (n && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\n'))
                    n--;
                if (n == 10 && strncmp(s, "extern \"C\"", 10) == 0) {
                    open_extern++;
                    sl = 0;
                    stmt_line = line;
                    continue;
                }
            }
            if (depth == 0)
                skipping = 1;
            depth++;
            continue;
        }
        if (*p == '}') {
            if (depth > 0)
                depth--;
            else if (open_extern > 0) {
                open_extern--;
                sl = 0;
                skipping = 0;
                stmt_line = line;
            }
            continue;
        }
        if (depth > 0)
            continue;
        if (*p == ';') {
            stmt[sl] = '\0';
            if (!skipping) {
                const char *s = stmt;
                while (*s == ' ' || *s == '\t' || *s == '\n')
                    s++;
                const char *paren = strchr(s, '(');
                if (paren && strncmp(s, "typedef", 7) != 0 && strncmp(s, "static", 6) != 0 &&
                    strncmp(s, "extern \"C\"", 10) != 0) {
                    const char *e = paren;
                    while (e > s && (e[-1] == ' ' || e[-1] == '\n'))
                        e--;
                    const char *b = e;
                    while (b > s && is_ident(b[-1]))
                        b--;
                    if (e > b && b[0] != '_') {
                        char name[NAME_LEN];
                        size_t n = (size_t)(e - b) < sizeof name - 1 ? (size_t)(e - b)
                                                                       : sizeof name - 1;
                        memcpy(name, b, n);
                        name[n] = '\0';
                        fn(h, name, stmt_line);
                    }
                }
            }
            sl = 0;
            skipping = 0;
            stmt_line = line;
            continue;
        }
        if (sl == 0 && (*p == ' ' || *p == '\n' || *p == '\t'))
            stmt_line = line + (*p == '\n' ? 0 : 0);
        if (sl + 1 < sizeof stmt)
            stmt[sl++] = *p;
    }
}

static int sibling_source(const file *h)
{
    for (int i = 0; i < n_files; i++)
        if (!files[i].is_header && files[i].room == h->room && strcmp(files[i].stem, h->stem) == 0)
            return i;
    return -1;
}

static void check_one_declaration(const file *h, const char *name, int line)
{
    (void)line;
    int own = is_face(h) ? -1 : sibling_source(h);
    if (own >= 0 && defines(files[own].text, name))
        return;
    int where = -1;
    for (int i = 0; i < n_files && where < 0; i++)
        if (!files[i].is_header && defines(files[i].text, name))
            where = i;
    if (where < 0)
        return; /* defined nowhere we look (a macro, a library): not the house's to judge */
    if (own < 0 && !is_face(h)) {
        breach("%s: declares %s(), which %s defines, but is named after no file: a private "
               "header is named after the file that implements it", h->path, name,
               files[where].path);
        return;
    }
    if (own >= 0)
        breach("%s: declares %s(), which %s defines: a header belongs to the file it is named "
               "after (%s)", h->path, name, files[where].path, files[own].path);
    else if (files[where].room != h->room)
        breach("%s: declares %s(), which %s defines, in another room", h->path, name,
               files[where].path);
}

/* Rule 3. */
static void check_ownership(void)
{
    for (int i = 0; i < n_files; i++)
        if (files[i].checked == 2 && files[i].is_header)
            declared_functions(&files[i], check_one_declaration, 0);
}

/* Rule 4: units, their dependencies, and a depth-first search for a way back. */
static int n_units;
static int unit_file[MAX_FILES]; /* a file naming the unit, for messages */
static unsigned char *dep;       /* n_units x n_units */
static int state[MAX_FILES];     /* 0 new, 1 on the path, 2 done */
static int path_stack[MAX_FILES], path_len;

static void make_units(void)
{
    for (int i = 0; i < n_files; i++)
        files[i].unit = -1;
    for (int i = 0; i < n_files; i++) {
        if (files[i].unit >= 0)
            continue;
        files[i].unit = n_units;
        unit_file[n_units] = i;
        if (!is_face(&files[i]))
            for (int j = i + 1; j < n_files; j++)
                if (files[j].unit < 0 && !is_face(&files[j]) && files[j].room == files[i].room &&
                    strcmp(files[j].stem, files[i].stem) == 0 &&
                    strcmp(files[j].path, files[i].path) != 0)
                    files[j].unit = n_units;
        n_units++;
    }
    dep = calloc((size_t)n_units * (size_t)n_units, 1);
    if (!dep) {
        breach("out of memory");
        return;
    }
    for (int i = 0; i < n_files; i++)
        for (int k = 0; k < files[i].n_inc; k++) {
            int a = files[i].unit, b = files[files[i].inc[k]].unit;
            if (a != b)
                dep[(size_t)a * (size_t)n_units + (size_t)b] = 1;
        }
}

static void unit_name(int u, char *buf, size_t len)
{
    const file *f = &files[unit_file[u]];
    const char *dot = strrchr(f->path, '.');
    if (is_face(f) || !dot)
        snprintf(buf, len, "%s", f->path);
    else
        snprintf(buf, len, "%.*s.{c,h}", (int)(dot - f->path), f->path);
}

static void visit(int u)
{
    state[u] = 1;
    path_stack[path_len++] = u;
    for (int v = 0; v < n_units; v++) {
        if (!dep[(size_t)u * (size_t)n_units + (size_t)v] || files[unit_file[v]].checked != 2)
            continue; /* sim/ and vision/ are below every checked room: no loop passes them */
        if (state[v] == 1) {
            char msg[2048] = "", name[PATH_LEN];
            int start = 0;
            while (path_stack[start] != v)
                start++;
            for (int k = start; k < path_len; k++) {
                unit_name(path_stack[k], name, sizeof name);
                strncat(msg, name, sizeof msg - strlen(msg) - 1);
                strncat(msg, " -> ", sizeof msg - strlen(msg) - 1);
            }
            unit_name(v, name, sizeof name);
            strncat(msg, name, sizeof msg - strlen(msg) - 1);
            breach("include loop: %s", msg);
        } else if (state[v] == 0) {
            visit(v);
        }
    }
    path_len--;
    state[u] = 2;
}

static void check_loops(void)
{
    if (!dep)
        return;
    for (int u = 0; u < n_units; u++)
        if (state[u] == 0 && files[unit_file[u]].checked == 2)
            visit(u);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: check_includes SOURCE_ROOT\n");
        return 2;
    }
    const char *root = argv[1];
    scan(root, "config", 2, 1);
    scan(root, "drivers", 2, 1); /* drivers/fuzz holds test harnesses, not the library */
    scan(root, "daemon", 2, 0);
    scan(root, "vision", 2, 0); /* its rooms (issue 34 G) */
    scan(root, "sim", 1, 1);    /* placed, and held to the floors; its own files' rules are its own */
    for (int r = 0; r < N_ROOMS; r++)
        for (int k = 0; k < 4 && rooms[r].face[k]; k++) {
            int found = 0;
            for (int i = 0; i < n_files && !found; i++)
                found = files[i].room == r && strcmp(files[i].name, rooms[r].face[k]) == 0;
            if (!found)
                breach("%s: its face %s is not in the tree", rooms[r].name, rooms[r].face[k]);
        }
    read_includes();
    check_floors_and_faces();
    check_ownership();
    make_units();
    check_loops();
    int includes = 0;
    for (int i = 0; i < n_files; i++)
        includes += files[i].n_inc;
    printf("check_includes: %d files, %d includes among them, %d units: %d breach%s\n", n_files,
           includes, n_units, breaches, breaches == 1 ? "" : "es");
    for (int i = 0; i < n_files; i++)
        free(files[i].text);
    free(dep);
    return breaches ? 1 : 0;
}
