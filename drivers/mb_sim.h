/* mb_sim.h: a simulated Modbus drive served with libmodbus (the "ribbon-sim" map of
 * rail_modbus_map.c), one rail_axis moving in real time, over TCP or over RTU on a
 * pseudo-terminal (rtu = true; mb_sim_path() names the pty a client opens as its serial line).
 *
 * Holding registers 0..63 are all readable (unused ones read 0) with function 3, writable with
 * functions 6 and 16; any standard Modbus TCP client can talk to it. Requests for another unit
 * id get exception 0x0B (gateway target failed to respond), as a gateway would answer. The
 * communication watchdog (register 14, ms) halts a moving axis and raises alarm 0x85 when no
 * request arrives in time. Faults: drop a fraction of requests unanswered, garble a fraction of
 * replies (bytes that are no Modbus frame), answer a fraction with exception 6 (busy), stall
 * the axis at a position (alarm 0x10, position deviation), raise an alarm after a time; on RTU
 * a garbled reply is a frame with a bad CRC, and wrong_id_prob answers as another slave.
 * On RTU, requests for another slave id are ignored (silence), as on a real bus.
 * Register 18 is an external load input (a torque monitor or following error, signed 16-bit):
 * it starts at load_counts and then holds whatever a client last wrote into it, so a test can
 * play the load sensor while the driver reads it (reg_load = 18). */
#ifndef RIBBON_DRIVERS_MB_SIM_H
#define RIBBON_DRIVERS_MB_SIM_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>

#include "rail.h"

typedef struct mb_sim_params {
    bool rtu;                  /* RTU on a pseudo-terminal instead of TCP */
    char host[64];             /* address to listen on: 127.0.0.1 */
    int port;                  /* TCP port; 0 = any free port (see mb_sim_port) */
    int slave;                 /* unit id answered, 1..247 */
    double counts_per_mm;      /* counts per mm of the simulated drive */
    double travel_mm;          /* mm, hard travel [0, travel] */
    double start_mm;           /* mm, position at start */
    double home_speed_mm_s;    /* mm/s */
    double drop_prob;          /* 0..1, requests left unanswered */
    double garble_prob;        /* 0..1, replies replaced by garbage bytes */
    double exception_prob;     /* 0..1, requests answered with exception 6 (busy) */
    double wrong_id_prob;      /* 0..1, RTU replies sent with another slave id (valid CRC) */
    double stall_at_mm;        /* mm, NaN = off */
    double alarm_after_s;      /* s after start, negative = off */
    int alarm_code;            /* drive alarm code for alarm_after_s */
    unsigned seed;             /* fault random stream */
    int load_counts;           /* initial value of register 18, the external load input (signed
                                  16-bit counts, -32768..32767): a torque or following-error
                                  reading that clients may overwrite (functions 6, 16) */
} mb_sim_params;

typedef struct mb_sim mb_sim;

mb_sim_params mb_sim_params_default(void);
rail_err mb_sim_open(mb_sim **out, const mb_sim_params *p, char *why, size_t why_len);
int mb_sim_port(const mb_sim *s);           /* TCP port */
const char *mb_sim_path(const mb_sim *s);   /* RTU: the pty path, "" for TCP */
rail_err mb_sim_step(mb_sim *s, double max_wait_s);
/* The axis's actual position (mm; a stalled axis where it stalled) as of the last step, and the
 * drive's time (its clock, s) of that step. Not thread-safe against mb_sim_step. */
void mb_sim_position(const mb_sim *s, double *mm, double *t_s);
/* Faults on command (not thread-safe against mb_sim_step): raise alarm `code` now (the axis
 * halts: a drive fault); deaf: requests are read and never answered (a cut cable: the axis goes
 * on until the communication watchdog halts it). */
void mb_sim_raise_alarm(mb_sim *s, int code);
void mb_sim_set_deaf(mb_sim *s, bool deaf);
rail_err mb_sim_run(mb_sim *s, double duration_s, volatile sig_atomic_t *stop);
void mb_sim_close(mb_sim *s);

#endif
