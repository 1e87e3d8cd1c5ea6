/* rail_serial_tty.c: the plain termios transport, for pseudo-terminals (simulators, tests) that
 * libserialport 0.1.1 refuses. Raw mode, 8N1, non-blocking descriptor with poll() timeouts.
 * A pty whose master side closed reads as EIO or POLLHUP: reported as disconnected. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

#include "rail_serial_tty.h"

typedef struct tty_serial {
    rail_serial base;
    int fd;
} tty_serial;

static int to_ms(double s)
{
    if (!(s > 0.0))
        return 0;
    if (s > 3600.0)
        s = 3600.0;
    return (int)(s * 1000.0 + 0.999);
}

static rail_err tty_write(rail_serial *s, const void *buf, size_t n, double timeout_s)
{
    tty_serial *t = (tty_serial *)s;
    const char *p = buf;
    size_t done = 0;
    for (int i = 0; i < 1000 && done < n; i++) {
        ssize_t w = write(t->fd, p + done, n - done);
        if (w > 0) {
            done += (size_t)w;
            continue;
        }
        if (w < 0 && errno != EAGAIN && errno != EINTR) {
            snprintf(s->why, sizeof s->why, "write to %.100s failed: %s", s->path, strerror(errno));
            return RAIL_E_DISCONNECTED;
        }
        struct pollfd pf = {t->fd, POLLOUT, 0};
        int r = poll(&pf, 1, to_ms(timeout_s));
        if (r == 0) {
            snprintf(s->why, sizeof s->why, "write to %.100s timed out", s->path);
            return RAIL_E_TIMEOUT;
        }
        if (r > 0 && (pf.revents & (POLLHUP | POLLERR)) && !(pf.revents & POLLOUT)) {
            snprintf(s->why, sizeof s->why, "%.100s hung up", s->path);
            return RAIL_E_DISCONNECTED;
        }
    }
    if (done < n) {
        snprintf(s->why, sizeof s->why, "write to %.100s stalled", s->path);
        return RAIL_E_TIMEOUT;
    }
    return RAIL_OK;
}

static rail_err tty_read(rail_serial *s, void *buf, size_t n, size_t *got, double timeout_s)
{
    tty_serial *t = (tty_serial *)s;
    *got = 0;
    struct pollfd pf = {t->fd, POLLIN, 0};
    int r;
    for (int i = 0; i < 16; i++) {
        r = poll(&pf, 1, to_ms(timeout_s));
        if (r >= 0 || errno != EINTR)
            break;
    }
    if (r == 0)
        return RAIL_OK;
    if (r < 0) {
        snprintf(s->why, sizeof s->why, "poll on %.100s failed: %s", s->path, strerror(errno));
        return RAIL_E_IO;
    }
    ssize_t k = read(t->fd, buf, n);
    if (k > 0) {
        *got = (size_t)k;
        return RAIL_OK;
    }
    if (k < 0 && (errno == EAGAIN || errno == EINTR))
        return RAIL_OK;
    snprintf(s->why, sizeof s->why, "%.100s hung up (%s)", s->path, k == 0 ? "end of file" : strerror(errno));
    return RAIL_E_DISCONNECTED;
}

static void tty_close(rail_serial *s)
{
    tty_serial *t = (tty_serial *)s;
    close(t->fd);
    free(t);
}

static const rail_serial_ops tty_ops = {"termios", tty_write, tty_read, tty_close};

static speed_t baud_code(int baud)
{
    switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    default: return 0;
    }
}

rail_err rail_serial_open_tty(rail_serial **out, const char *path, int baud, char *why, size_t why_len)
{
    *out = NULL;
    speed_t sp = baud_code(baud);
    if (!sp) {
        snprintf(why, why_len, "baud rate %d not supported (9600..230400)", baud);
        return RAIL_E_INVALID;
    }
    int fd = open(path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        snprintf(why, why_len, "open %.100s: %s", path, strerror(errno));
        return RAIL_E_IO;
    }
    struct termios tio;
    if (!isatty(fd) || tcgetattr(fd, &tio) != 0) {
        snprintf(why, why_len, "%.100s is not a terminal device", path);
        close(fd);
        return RAIL_E_IO;
    }
    cfmakeraw(&tio);
    tio.c_cflag |= CLOCAL | CREAD;
    tio.c_cflag &= ~(tcflag_t)(CSTOPB | PARENB | CRTSCTS);
    cfsetispeed(&tio, sp);
    cfsetospeed(&tio, sp);
    tio.c_cc[VMIN] = 0;
    tio.c_cc[VTIME] = 0;
    if (tcsetattr(fd, TCSANOW, &tio) != 0) {
        snprintf(why, why_len, "configuring %.100s: %s", path, strerror(errno));
        close(fd);
        return RAIL_E_IO;
    }
    tty_serial *t = calloc(1, sizeof *t);
    if (!t) {
        close(fd);
        snprintf(why, why_len, "out of memory");
        return RAIL_E_NOMEM;
    }
    t->base.ops = &tty_ops;
    rail_text_copy(t->base.path, sizeof t->base.path, path);
    t->fd = fd;
    *out = &t->base;
    return RAIL_OK;
}
