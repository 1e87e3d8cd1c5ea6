/* mb_sim.c: the simulated Modbus drive (see mb_sim.h; register layout in rail_modbus_map.c).
 *
 * TCP: one select() loop over the listening socket and up to 8 clients. RTU: libmodbus's RTU
 * server talks to one end of a socketpair and a relay copies bytes between the other end and a
 * pseudo-terminal master, which is where RTU faults (bad CRC, wrong slave id) are applied.
 * For each request: advance the axis, refresh the read-only registers, let the fault injector
 * decide, reply with libmodbus, then act on a non-zero command register (and clear it: the
 * command register is a trigger).
 * Read-only registers (8..13, 16, 17) are rewritten from the axis before every reply, so a
 * client writing them changes nothing. Register 18 is the external load input: nothing in the
 * simulator writes it after start (mb_sim_params.load_counts), so whoever plays the drive's load
 * sensor writes it (function 6 or 16) and every reader then sees that value. */
#define _XOPEN_SOURCE 700
#include "mb_sim.h"

#include <arpa/inet.h>
#include <errno.h>
#include <math.h>
#include <modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include "rail_axis.h"
#include "rail_clock.h"
#include "rail_modbus_map.h"
#include "rail_sim.h"

#define MBS_CLIENTS 8
#define MBS_REGS 64
#define MBS_REG_LOAD 18 /* external load: written by the test or a client, never by the axis */

enum { ST_READY = 1, ST_MOVING = 2, ST_INPOS = 4, ST_HOMING = 8, ST_HOMED = 16, ST_ALARM = 32 };
enum { CORRUPT_CRC = 1, CORRUPT_ID = 2 };
enum { ALM_DEVIATION = 0x10, ALM_OVERTRAVEL = 0x66, ALM_DATA = 0x70, ALM_COMM_TIMEOUT = 0x85 };

struct mb_sim {
    mb_sim_params p;
    modbus_t *ctx;
    modbus_mapping_t *map;
    int listen_fd;
    int clients[MBS_CLIENTS];
    int port;
    int master, slave;  /* RTU: pty ends (the slave is held open in raw mode) */
    int sv[2];          /* RTU: [0] libmodbus server side, [1] relay side */
    char path[128];     /* RTU: pty slave path */
    int corrupt;        /* RTU: fault to apply to the next reply (0, CORRUPT_CRC, CORRUPT_ID) */
    rail_clock clock;
    double t_start, t_last, t_request;
    rail_axis ax;
    bool homing, stalled, alarm_fired;
    bool deaf;          /* requests read, never answered (mb_sim_set_deaf) */
    int alarm;         /* current alarm code, 0 = none */
    unsigned rng;
};

mb_sim_params mb_sim_params_default(void)
{
    mb_sim_params p;
    memset(&p, 0, sizeof p);
    snprintf(p.host, sizeof p.host, "127.0.0.1");
    p.port = 1502;
    p.slave = 1;
    p.counts_per_mm = 1000.0;
    p.travel_mm = 200.0;
    p.home_speed_mm_s = 20.0;
    p.stall_at_mm = NAN;
    p.alarm_after_s = -1.0;
    p.alarm_code = 0x30;
    p.seed = 4242u;
    p.load_counts = 0;
    return p;
}

static void raise_alarm(mb_sim *s, int code)
{
    rail_axis_halt(&s->ax);
    s->homing = false;
    s->alarm = code;
}

static void advance(mb_sim *s)
{
    double now = rail_clock_now(s->clock);
    double dt = now - s->t_last;
    s->t_last = now;
    if (!s->alarm_fired && s->p.alarm_after_s >= 0.0 && now - s->t_start >= s->p.alarm_after_s) {
        s->alarm_fired = true;
        raise_alarm(s, s->p.alarm_code);
    }
    uint16_t *R = s->map->tab_registers;
    double wd = R[14] / 1000.0;
    if (wd > 0.0 && rail_axis_busy(&s->ax) && now - s->t_request > wd)
        raise_alarm(s, ALM_COMM_TIMEOUT);
    if (dt > 0.0 && rail_axis_busy(&s->ax)) {
        double before = s->ax.pos_mm;
        rail_axis_step(&s->ax, dt);
        double st = s->p.stall_at_mm;
        if (!isnan(st) && !s->stalled && rail_sim_crossed(before, s->ax.pos_mm, st)) {
            s->stalled = true;
            s->ax.pos_mm = st;
            raise_alarm(s, ALM_DEVIATION);
        }
        if (s->ax.limit_hit) {
            s->ax.limit_hit = false;
            raise_alarm(s, ALM_OVERTRAVEL);
        }
        if (s->homing && !rail_axis_busy(&s->ax))
            s->homing = false;
    }
}

static void refresh(mb_sim *s)
{
    uint16_t *R = s->map->tab_registers;
    double c = s->p.counts_per_mm;
    rail_mb_put32(R + 8, (int32_t)lround(s->ax.pos_mm * c), RAIL_MB_HIGH_FIRST);
    rail_mb_put32(R + 10, (int32_t)lround(s->ax.vel_mm_s * c), RAIL_MB_HIGH_FIRST);
    uint16_t st = 0;
    bool busy = rail_axis_busy(&s->ax);
    if (s->alarm)
        st |= ST_ALARM;
    else if (!busy)
        st |= ST_READY;
    if (busy)
        st |= ST_MOVING;
    if (s->homing)
        st |= ST_HOMING;
    if (s->ax.homed)
        st |= ST_HOMED;
    if (!busy && fabs(s->ax.pos_mm - s->ax.target_mm) < 0.5 / c)
        st |= ST_INPOS;
    R[12] = st;
    R[13] = (uint16_t)s->alarm;
    R[16] = 0x5242;
    R[17] = 1;
}

static void command(mb_sim *s)
{
    uint16_t *R = s->map->tab_registers;
    uint16_t cmd = R[6];
    if (!cmd)
        return;
    R[6] = 0;
    double c = s->p.counts_per_mm;
    switch (cmd) {
    case 1: {
        if (s->alarm)
            return; /* a drive in alarm ignores start */
        double target = rail_mb_get32(R + 0, RAIL_MB_HIGH_FIRST) / c;
        double speed = rail_mb_get32(R + 2, RAIL_MB_HIGH_FIRST) / c;
        double accel = rail_mb_get32(R + 4, RAIL_MB_HIGH_FIRST) / c;
        if (!(speed > 0.0) || !(accel > 0.0) || target < 0.0 || target > s->p.travel_mm) {
            raise_alarm(s, ALM_DATA);
            return;
        }
        s->ax.accel_mm_s2 = accel;
        rail_axis_move_to(&s->ax, target, speed);
        break;
    }
    case 2:
        rail_axis_stop(&s->ax);
        break;
    case 3:
        rail_axis_halt(&s->ax);
        s->homing = false;
        break;
    case 4:
        if (s->alarm)
            return;
        rail_axis_home(&s->ax, s->p.home_speed_mm_s);
        s->homing = true;
        break;
    case 5:
        if (!rail_axis_busy(&s->ax)) {
            s->alarm = 0;
            s->stalled = false;
            s->p.stall_at_mm = NAN;
        }
        break;
    default:
        break;
    }
}

static void drop_client(mb_sim *s, int i)
{
    close(s->clients[i]);
    s->clients[i] = -1;
}

/* Handle one request waiting on the context's current socket; returns false if the link broke. */
static bool serve_request(mb_sim *s, int client_fd)
{
    uint8_t q[MODBUS_TCP_MAX_ADU_LENGTH];
    int rc = modbus_receive(s->ctx, q);
    if (rc <= 0)
        return rc == 0; /* 0: a request for another slave (RTU), ignored */
    advance(s);
    if (s->deaf)
        return true; /* the request is lost on the way: no reply, the watchdog is not fed */
    int hl = modbus_get_header_length(s->ctx); /* TCP 7 (unit id is q[6]), RTU 1 (q[0]) */
    int unit = q[hl - 1];
    if (!s->p.rtu && unit != s->p.slave && unit != 0xff && unit != 0) {
        modbus_reply_exception(s->ctx, q, MODBUS_EXCEPTION_GATEWAY_TARGET);
        return true;
    }
    s->t_request = rail_clock_now(s->clock);
    if (s->p.drop_prob > 0.0 && rail_sim_rand(&s->rng) < s->p.drop_prob)
        return true;
    if (s->p.garble_prob > 0.0 && rail_sim_rand(&s->rng) < s->p.garble_prob) {
        if (s->p.rtu) {
            s->corrupt = CORRUPT_CRC; /* the relay spoils the reply's CRC */
        } else {
            /* Right transaction id, a well-formed frame of the wrong function with nonsense in
               it: a corrupted reply the client must refuse. */
            uint8_t fc = q[hl] == 0x06 ? 0x05 : 0x06;
            uint8_t g[12] = {q[0], q[1], 0x00, 0x00, 0x00, 0x06, q[6], fc, 0xee, 0x13, 0x37, 0x99};
            ssize_t w = send(client_fd, g, sizeof g, MSG_NOSIGNAL);
            (void)w;
            return true;
        }
    } else if (s->p.rtu && s->p.wrong_id_prob > 0.0 && rail_sim_rand(&s->rng) < s->p.wrong_id_prob) {
        s->corrupt = CORRUPT_ID;
    }
    if (s->p.exception_prob > 0.0 && rail_sim_rand(&s->rng) < s->p.exception_prob) {
        modbus_reply_exception(s->ctx, q, MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY);
        return true;
    }
    refresh(s);
    modbus_reply(s->ctx, q, rc, s->map);
    command(s);
    refresh(s);
    return true;
}

static void serve(mb_sim *s, int i)
{
    modbus_set_socket(s->ctx, s->clients[i]);
    if (!serve_request(s, s->clients[i]))
        drop_client(s, i);
}

static uint16_t crc16(const uint8_t *b, size_t n)
{
    /* Modbus RTU CRC: reflected polynomial 0xA001, initial 0xFFFF, sent low byte first. */
    uint16_t c = 0xffff;
    for (size_t i = 0; i < n; i++) {
        c ^= b[i];
        for (int k = 0; k < 8; k++)
            c = (c & 1) ? (uint16_t)((c >> 1) ^ 0xa001) : (uint16_t)(c >> 1);
    }
    return c;
}

/* RTU: relay pty -> server, serve, relay replies server -> pty (with the RTU faults). */
static void rtu_step(mb_sim *s, double max_wait_s)
{
    struct pollfd pf = {s->master, POLLIN, 0};
    int r = poll(&pf, 1, max_wait_s > 0.0 ? (int)(max_wait_s * 1000.0) : 0);
    advance(s);
    if (r <= 0 || !(pf.revents & POLLIN))
        return;
    uint8_t buf[512];
    ssize_t n = read(s->master, buf, sizeof buf);
    if (n <= 0)
        return;
    if (write(s->sv[1], buf, (size_t)n) != n)
        return;
    serve_request(s, -1);
    ssize_t m = recv(s->sv[1], buf, sizeof buf, MSG_DONTWAIT);
    if (m >= 4) {
        if (s->corrupt == CORRUPT_CRC) {
            buf[m - 1] ^= 0x5a;
        } else if (s->corrupt == CORRUPT_ID) {
            buf[0] = (uint8_t)(buf[0] % 247 + 1);
            uint16_t c = crc16(buf, (size_t)m - 2);
            buf[m - 2] = (uint8_t)(c & 0xff);
            buf[m - 1] = (uint8_t)(c >> 8);
        }
        ssize_t w = write(s->master, buf, (size_t)m);
        (void)w;
    }
    s->corrupt = 0;
}

rail_err mb_sim_step(mb_sim *s, double max_wait_s)
{
    if (s->p.rtu) {
        rtu_step(s, max_wait_s);
        return RAIL_OK;
    }
    fd_set rd;
    FD_ZERO(&rd);
    FD_SET(s->listen_fd, &rd);
    int maxfd = s->listen_fd;
    for (int i = 0; i < MBS_CLIENTS; i++)
        if (s->clients[i] >= 0) {
            FD_SET(s->clients[i], &rd);
            maxfd = s->clients[i] > maxfd ? s->clients[i] : maxfd;
        }
    struct timeval tv = {0, (long)(max_wait_s > 0.0 ? max_wait_s * 1e6 : 0)};
    int r = select(maxfd + 1, &rd, NULL, NULL, &tv);
    advance(s);
    if (r <= 0)
        return RAIL_OK;
    if (FD_ISSET(s->listen_fd, &rd)) {
        int fd = accept(s->listen_fd, NULL, NULL);
        if (fd >= 0) {
            int slot = -1;
            for (int i = 0; i < MBS_CLIENTS && slot < 0; i++)
                if (s->clients[i] < 0)
                    slot = i;
            if (slot < 0)
                close(fd); /* full: like a drive with few connection slots */
            else
                s->clients[slot] = fd;
        }
    }
    for (int i = 0; i < MBS_CLIENTS; i++)
        if (s->clients[i] >= 0 && FD_ISSET(s->clients[i], &rd))
            serve(s, i);
    return RAIL_OK;
}

static rail_err step_any(void *s, double max_wait_s)
{
    return mb_sim_step(s, max_wait_s);
}

rail_err mb_sim_run(mb_sim *s, double duration_s, volatile sig_atomic_t *stop)
{
    return rail_sim_run(step_any, s, s->clock, duration_s, stop);
}

rail_err mb_sim_open(mb_sim **out, const mb_sim_params *p, char *why, size_t why_len)
{
    *out = NULL;
    if (!p || p->slave < 1 || p->slave > 247 || !(p->counts_per_mm > 0.0) || !(p->travel_mm > 0.0) ||
        !(p->start_mm >= 0.0 && p->start_mm <= p->travel_mm) || p->port < 0 || p->port > 65535 ||
        !(p->home_speed_mm_s > 0.0)) {
        snprintf(why, why_len, "mbsim: slave must be 1..247, port 0..65535, counts_per_mm, travel and "
                         "home speed positive, start inside the travel");
        return RAIL_E_INVALID;
    }
    if (p->load_counts < -32768 || p->load_counts > 32767) {
        snprintf(why, why_len, "mbsim: load_counts %d outside the signed 16-bit range", p->load_counts);
        return RAIL_E_INVALID;
    }
    mb_sim *s = calloc(1, sizeof *s);
    if (!s) {
        snprintf(why, why_len, "mbsim: out of memory");
        return RAIL_E_NOMEM;
    }
    s->p = *p;
    s->listen_fd = -1;
    for (int i = 0; i < MBS_CLIENTS; i++)
        s->clients[i] = -1;
    s->master = s->slave = s->sv[0] = s->sv[1] = -1;
    s->ctx = p->rtu ? modbus_new_rtu("/dev/null", 19200, 'E', 8, 1) : modbus_new_tcp(p->host, p->port);
    s->map = modbus_mapping_new(0, 0, MBS_REGS, 0);
    if (!s->ctx || !s->map) {
        snprintf(why, why_len, "mbsim: cannot create the libmodbus server: %s", modbus_strerror(errno));
        mb_sim_close(s);
        return RAIL_E_NOMEM;
    }
    s->map->tab_registers[MBS_REG_LOAD] = (uint16_t)(int16_t)p->load_counts;
    modbus_set_slave(s->ctx, p->slave);
    modbus_set_indication_timeout(s->ctx, 0, 500000);
    if (p->rtu) {
        /* The server never opens a device: it reads and writes a socketpair, relayed to a pty. */
        if (rail_sim_pty_open(&s->master, &s->slave, s->path, sizeof s->path) != RAIL_SIM_PTY_OK ||
            socketpair(AF_UNIX, SOCK_STREAM, 0, s->sv) != 0) {
            snprintf(why, why_len, "mbsim: cannot set up the RTU pseudo-terminal: %s", strerror(errno));
            mb_sim_close(s);
            return RAIL_E_IO;
        }
        modbus_set_socket(s->ctx, s->sv[0]);
    } else {
        s->listen_fd = modbus_tcp_listen(s->ctx, 4);
        if (s->listen_fd < 0) {
            snprintf(why, why_len, "mbsim: cannot listen on %s:%d: %s", p->host, p->port, modbus_strerror(errno));
            mb_sim_close(s);
            return RAIL_E_IO;
        }
        struct sockaddr_in sa;
        socklen_t sl = sizeof sa;
        s->port = p->port;
        if (getsockname(s->listen_fd, (struct sockaddr *)&sa, &sl) == 0)
            s->port = ntohs(sa.sin_port);
    }
    s->clock = rail_clock_real();
    s->t_start = s->t_last = s->t_request = rail_clock_now(s->clock);
    s->ax = rail_axis_make(p->start_mm, 100.0, p->travel_mm);
    s->rng = rail_sim_seed(p->seed);
    refresh(s);
    *out = s;
    return RAIL_OK;
}

int mb_sim_port(const mb_sim *s)
{
    return s->port;
}

const char *mb_sim_path(const mb_sim *s)
{
    return s->path;
}

void mb_sim_close(mb_sim *s)
{
    if (!s)
        return;
    for (int i = 0; i < MBS_CLIENTS; i++)
        if (s->clients[i] >= 0)
            close(s->clients[i]);
    if (s->listen_fd >= 0)
        close(s->listen_fd);
    if (s->p.rtu) {
        int fds[4] = {s->master, s->slave, s->sv[0], s->sv[1]};
        for (int i = 0; i < 4; i++)
            if (fds[i] >= 0)
                close(fds[i]);
    }
    if (s->map)
        modbus_mapping_free(s->map);
    if (s->ctx) {
        modbus_set_socket(s->ctx, -1);
        modbus_free(s->ctx);
    }
    free(s);
}

void mb_sim_position(const mb_sim *s, double *mm, double *t_s)
{
    *mm = s->ax.pos_mm;
    if (t_s)
        *t_s = s->t_last;
}

void mb_sim_raise_alarm(mb_sim *s, int code)
{
    raise_alarm(s, code);
}

void mb_sim_set_deaf(mb_sim *s, bool deaf)
{
    s->deaf = deaf;
}
