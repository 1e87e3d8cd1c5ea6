/*
 * plot_session.c: the PLplot lifecycle of one figure, and the containment of PLplot's errors.
 *
 * What PLplot 5.15 (Debian) does, found by reading src/plctrl.c, src/plcore.c and drivers/cairo.c
 * and by trying it:
 *
 *   - Global state. PLplot keeps a table of streams and a "current stream" pointer in globals, and
 *     its exit/abort handlers are process-wide. So every figure takes plot_lock (one mutex), makes
 *     its own stream with plmkstrm, ends it with plend1 (which frees the stream slot) and puts back
 *     whatever stream was current before. Nothing of a figure outlives the call. The exit handler
 *     is set for the figure and put back to PLplot's default afterwards (PLplot has no getter, so
 *     a handler some other code had installed would be lost: nothing else here uses PLplot).
 *   - Fatal errors. plexit() calls the handler set with plsexit(), then plend() and exit() no matter
 *     what the handler returns: a handler cannot veto the exit. The only way back is not to return:
 *     our handler longjmps to the setjmp in plot_session_run (the jump target lives in plot_fatal,
 *     guarded by plot_lock, because plsexit takes no user pointer). After the jump the stream is
 *     ended under a second guard; if that too fails the stream slot is abandoned (a small leak, but
 *     the process lives and the caller gets PLplot's message).
 *   - Avoidable fatal paths are avoided rather than caught: an unknown device makes plinit() prompt
 *     on stdin (then plexit at EOF), so the device is looked up with plgDevs() first; an output
 *     file PLplot cannot open makes it retry fopen 11 times and plexit, so we open the file
 *     ourselves (mkstemp next to the target) and hand PLplot a FILE* with plsfile(). PLplot
 *     fcloses that FILE in plend1 (the cairo driver's tidy calls plCloseFile), so it gets a dup of
 *     our descriptor and we keep the original to verify the file.
 *   - Non-fatal errors. plabort() prints to stderr and carries on, unless the stream has an error
 *     buffer set with plsError(): then it only sets the stream's error code and message. Each
 *     session sets one, and any abort fails the figure with PLplot's message.
 *   - Silent write errors. The pngcairo driver writes the PNG in plend1 through a stream callback
 *     whose errors are ignored, so the file is checked afterwards: PNG signature, IHDR width and
 *     height as asked, and the IEND chunk at the very end (a full disk shows as a truncated file).
 *   - Drivers. Debian's PLplot loads drivers (cairo.so) from its compiled-in directory
 *     /usr/lib/<arch>/plplot5.15.0/drivers; no PLPLOT_* environment variable is needed (the tests
 *     run without one).
 *   - Locale. PLplot switches LC_NUMERIC to "C" around its drawing calls with setlocale(), which is
 *     process-wide: harmless here (the daemon never changes the locale), noted for the future.
 *   - Memory. PLplot frees its streams and the cairo surfaces. Text goes through pango, whose font
 *     map keeps the fontconfig patterns of every text size it has seen until exit: constant for
 *     repeated figures of one size, a few tens of kB more for each new page size. LeakSanitizer
 *     reports those patterns as lost because fontconfig links them by offsets, not pointers;
 *     tests/daemon/test_plot_lsan.supp suppresses libfontconfig frames, and nothing else.
 */
#include "plot_session.h"

#include "plot_style.h"

#include <errno.h>
#include <fcntl.h>
#include <plplot.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define PLOT_ERRMSG_LEN 1024 /* plabort sprintf()s "<message>, aborting operation\n" into it */
#define PLOT_MAX_DEVICES 128

/* PLplot's handlers are process-wide and take no context pointer, so the jump target and the
 * message of a fatal error have to be file-scope. Only touched with plot_lock held. */
static pthread_mutex_t plot_lock = PTHREAD_MUTEX_INITIALIZER;
static struct {
    jmp_buf *target;
    char msg[512];
} plot_fatal;

static int plot_on_fatal(const char *msg)
{
    snprintf(plot_fatal.msg, sizeof plot_fatal.msg, "%s", msg && *msg ? msg : "fatal error");
    if (plot_fatal.target)
        longjmp(*plot_fatal.target, 1);
    return 1; /* no target: PLplot goes on to exit(1); cannot happen while plot_lock is held */
}

plot_status plot_fail(plot_status st, char *why, size_t why_len, const char *fmt, ...)
{
    if (why && why_len > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(why, why_len, fmt, ap);
        va_end(ap);
    }
    return st;
}

plot_status plot_size_resolve(int requested, int def, const char *name, int *out, char *why, size_t why_len)
{
    int v = requested == 0 ? def : requested;
    if (v < PLOT_SIZE_MIN || v > PLOT_SIZE_MAX)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "%s_px = %d is out of range [%d, %d] (0 = default %d)",
                         name, requested, PLOT_SIZE_MIN, PLOT_SIZE_MAX, def);
    *out = v;
    return PLOT_OK;
}

/* State of one session, kept outside the frame that calls setjmp so that its values are well
 * defined after a longjmp (C17 7.13.2.1p3 only covers the setjmp caller's own locals). */
typedef struct plot_session {
    const char *device;
    const char *png_path;
    int width, height;
    plot_draw_fn draw;
    void *ctx;
    char *tmp_path;     /* png_path + ".XXXXXX", created by mkstemp */
    int fd;             /* our descriptor of tmp_path, -1 when closed */
    FILE *handed;       /* the FILE* given to PLplot (a dup of fd); PLplot fcloses it in plend1 */
    PLINT prev_stream;  /* current stream before we started */
    PLINT stream;       /* our stream, -1 when none */
    bool stream_open;   /* plend1 still owed */
    PLINT errcode;      /* set to 1 by plabort (plsError) */
    char errmsg[PLOT_ERRMSG_LEN];
} plot_session;

static bool device_available(const char *device)
{
    const char *menu_arr[PLOT_MAX_DEVICES];
    const char *name_arr[PLOT_MAX_DEVICES];
    const char **menu = menu_arr, **names = name_arr;
    int n = PLOT_MAX_DEVICES;
    plgDevs(&menu, &names, &n);
    for (int i = 0; i < n; i++)
        if (names[i] && strcmp(names[i], device) == 0)
            return true;
    return false;
}

/* PNG layout: 8-byte signature, then chunks (length, type, data, CRC). The first chunk is IHDR,
 * whose data begins with width and height (big-endian uint32); the last is the empty IEND. */
static plot_status verify_png(int fd, const char *path, int width, int height, char *why, size_t why_len)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    static const unsigned char iend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};
    struct stat st;
    unsigned char head[24], tail[12];
    if (fstat(fd, &st) != 0)
        return plot_fail(PLOT_ERR_IO, why, why_len, "cannot stat %s: %s", path, strerror(errno));
    if (st.st_size < (off_t)(sizeof head + sizeof tail))
        return plot_fail(PLOT_ERR_IO, why, why_len,
                         "PLplot wrote only %lld bytes to %s (disk full, or the driver failed)",
                         (long long)st.st_size, path);
    if (pread(fd, head, sizeof head, 0) != (ssize_t)sizeof head ||
        pread(fd, tail, sizeof tail, st.st_size - (off_t)sizeof tail) != (ssize_t)sizeof tail)
        return plot_fail(PLOT_ERR_IO, why, why_len, "cannot read back %s: %s", path,
                         errno ? strerror(errno) : "short read");
    if (memcmp(head, sig, sizeof sig) != 0 || memcmp(head + 12, "IHDR", 4) != 0)
        return plot_fail(PLOT_ERR_IO, why, why_len, "%s is not a PNG file after plotting", path);
    uint32_t w = (uint32_t)head[16] << 24 | (uint32_t)head[17] << 16 | (uint32_t)head[18] << 8 | head[19];
    uint32_t h = (uint32_t)head[20] << 24 | (uint32_t)head[21] << 16 | (uint32_t)head[22] << 8 | head[23];
    if (w != (uint32_t)width || h != (uint32_t)height)
        return plot_fail(PLOT_ERR_IO, why, why_len, "%s is %ux%u px, expected %dx%d", path, (unsigned)w,
                         (unsigned)h, width, height);
    if (memcmp(tail, iend, sizeof iend) != 0)
        return plot_fail(PLOT_ERR_IO, why, why_len, "%s is truncated (no IEND chunk at the end; disk full?)", path);
    return PLOT_OK;
}

static void session_discard_file(plot_session *s)
{
    if (s->fd >= 0) {
        close(s->fd);
        s->fd = -1;
    }
    if (s->tmp_path)
        unlink(s->tmp_path);
}

/* Creates the stream, draws, ends the stream. Called with the fatal guard armed. */
static plot_status session_draw(plot_session *s, char *why, size_t why_len)
{
    if (!device_available(s->device))
        return plot_fail(PLOT_ERR_DEVICE, why, why_len,
                         "PLplot has no '%s' device (install plplot-driver-cairo; drivers are looked up in "
                         "PLplot's installed driver directory)",
                         s->device);

    int dupfd = dup(s->fd);
    if (dupfd < 0)
        return plot_fail(PLOT_ERR_IO, why, why_len, "cannot duplicate the descriptor of %s: %s", s->tmp_path,
                         strerror(errno));
    FILE *f = fdopen(dupfd, "wb");
    if (!f) {
        int e = errno;
        close(dupfd);
        return plot_fail(PLOT_ERR_IO, why, why_len, "cannot open a stream on %s: %s", s->tmp_path, strerror(e));
    }

    plgstrm(&s->prev_stream);
    PLINT strm = -1;
    plmkstrm(&strm);
    if (strm < 0) {
        fclose(f);
        plsstrm(s->prev_stream);
        return plot_fail(PLOT_ERR_PLPLOT, why, why_len, "PLplot could not create a new stream (all in use)");
    }
    s->stream = strm;
    s->stream_open = true;
    plsError(&s->errcode, s->errmsg);
    plsdev(s->device);
    plsfile(f);
    s->handed = f; /* from here PLplot owns f and fcloses it in plend1 */
    plspause(0);
    plspage(0.0, 0.0, s->width, s->height, 0, 0);
    plot_style_palette();
    plinit();

    plot_status st = PLOT_OK;
    if (s->errcode == 0) {
        plot_style_defaults();
        st = s->draw(s->ctx, why, why_len);
    }
    plend1(); /* writes the PNG (eop), closes f, frees the stream */
    s->stream_open = false;
    s->handed = NULL;
    plsstrm(s->prev_stream);

    if (s->errcode != 0) {
        size_t len = strcspn(s->errmsg, "\n");
        const char *m = s->errmsg;
        if (len == 0 && m[0] == '\n') { /* "\n*** PLPLOT ERROR ..." form */
            m++;
            len = strcspn(m, "\n");
        }
        return plot_fail(PLOT_ERR_PLPLOT, why, why_len, "PLplot: %.*s", (int)len, m);
    }
    return st;
}

/* After a longjmp out of PLplot: end our stream if one is open, under a second guard. */
static void session_recover(plot_session *s)
{
    if (s->stream_open) {
        jmp_buf again;
        plot_fatal.target = &again;
        if (setjmp(again) == 0) {
            plsstrm(s->stream);
            plend1(); /* also fcloses the handed FILE */
            s->handed = NULL;
        }
        /* else: plend1 itself failed fatally: the stream slot (and FILE) is abandoned */
        s->stream_open = false;
        plsstrm(s->prev_stream);
    } else if (s->handed) {
        fclose(s->handed);
    }
    s->handed = NULL;
}

static plot_status session_run_locked(plot_session *s, char *why, size_t why_len)
{
    jmp_buf env;
    plot_fatal.target = &env;
    plot_fatal.msg[0] = '\0';
    plsexit(plot_on_fatal);

    plot_status st;
    if (setjmp(env) == 0) {
        st = session_draw(s, why, why_len);
    } else {
        char msg[sizeof plot_fatal.msg];
        snprintf(msg, sizeof msg, "%s", plot_fatal.msg);
        session_recover(s);
        st = plot_fail(PLOT_ERR_PLPLOT, why, why_len, "PLplot fatal error (caught, not exiting): %s", msg);
    }
    plot_fatal.target = NULL;
    plsexit(NULL);
    return st;
}

plot_status plot_session_run(const char *device, const char *png_path, int width_px, int height_px,
                             plot_draw_fn draw, void *ctx, char *why, size_t why_len)
{
    if (why && why_len)
        why[0] = '\0';
    if (!device || !*device || !draw)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "plot_session_run: no device or no drawing function");
    if (!png_path || !*png_path)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "no output path given");
    if (width_px < PLOT_SIZE_MIN || width_px > PLOT_SIZE_MAX || height_px < PLOT_SIZE_MIN ||
        height_px > PLOT_SIZE_MAX)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "image size %dx%d px is out of range [%d, %d]", width_px,
                         height_px, PLOT_SIZE_MIN, PLOT_SIZE_MAX);

    plot_session s = {.device = device, .png_path = png_path, .width = width_px, .height = height_px,
                      .draw = draw, .ctx = ctx, .fd = -1, .stream = -1};
    size_t plen = strlen(png_path);
    s.tmp_path = malloc(plen + 8);
    if (!s.tmp_path)
        return plot_fail(PLOT_ERR_IO, why, why_len, "out of memory");
    memcpy(s.tmp_path, png_path, plen);
    memcpy(s.tmp_path + plen, ".XXXXXX", 8);
    s.fd = mkstemp(s.tmp_path);
    if (s.fd < 0) {
        int e = errno;
        free(s.tmp_path);
        return plot_fail(PLOT_ERR_IO, why, why_len, "cannot create %s (a temporary file beside it): %s", png_path,
                         strerror(e));
    }
    /* mkstemp makes 0600; a report is an ordinary file: apply the umask like fopen would */
    mode_t um = umask(0);
    umask(um);
    (void)fchmod(s.fd, 0666 & ~um);

    pthread_mutex_lock(&plot_lock);
    plot_status st = session_run_locked(&s, why, why_len);
    pthread_mutex_unlock(&plot_lock);

    if (st == PLOT_OK)
        st = verify_png(s.fd, png_path, s.width, s.height, why, why_len);
    if (st == PLOT_OK && close(s.fd) != 0) {
        s.fd = -1;
        st = plot_fail(PLOT_ERR_IO, why, why_len, "cannot write %s: %s", png_path, strerror(errno));
    }
    if (st == PLOT_OK) {
        s.fd = -1;
        if (rename(s.tmp_path, png_path) != 0)
            st = plot_fail(PLOT_ERR_IO, why, why_len, "cannot rename %s to %s: %s", s.tmp_path, png_path,
                           strerror(errno));
    }
    if (st != PLOT_OK)
        session_discard_file(&s);
    free(s.tmp_path);
    return st;
}
