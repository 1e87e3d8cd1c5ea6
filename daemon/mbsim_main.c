/* mbsim_main.c: `ribbon-mbsim`, the simulated Modbus drive (logic in drivers/mb_sim.c).
 * `ribbon-mbsim --listen 127.0.0.1:PORT [--slave N]` prints "listening: HOST:PORT" as its first
 * line (PORT 0 picks a free port and prints it); `--rtu` serves Modbus RTU on a pseudo-terminal
 * instead and prints "pty: PATH". Serves until SIGINT/SIGTERM (the handler only sets a flag). */
#include <stdio.h>
#include <string.h>

#include "mb_sim.h"
#include "cli.h"

#define PROG "ribbon-mbsim"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ribbon-mbsim --listen HOST:PORT [options]\n"
            "  --listen HOST:PORT   address to serve Modbus TCP on (default 127.0.0.1:1502)\n"
            "  --rtu                serve Modbus RTU on a pseudo-terminal instead (prints pty: PATH)\n"
            "  --slave N            unit id answered, 1..247 (default 1)\n"
            "  --counts-per-mm C    drive counts per mm (default 1000)\n"
            "  --travel MM          hard travel (default 200)\n"
            "  --start MM           position at start (default 0)\n"
            "  --drop P             leave a fraction P of requests unanswered\n"
            "  --garble P           answer a fraction P with a corrupted frame (RTU: bad CRC)\n"
            "  --exception P        answer a fraction P with exception 6 (busy)\n"
            "  --wrong-id P         RTU: answer a fraction P as another slave id\n"
            "  --stall MM           stall (alarm 0x10) when the axis reaches MM\n"
            "  --alarm-after S      raise an alarm S seconds after start\n"
            "  --alarm-code N       alarm code for --alarm-after (default 0x30)\n"
            "  --seed N             fault random seed\n"
            "  --load N             initial external load, register 18 (signed 16-bit counts)\n"
            "  --duration S         exit after S seconds (default: until signalled)\n"
            "Registers: see drivers/rail_modbus_map.c (map \"ribbon-sim\").\n");
}

static int num(const char *opt, const char *v, double lo, double hi, double *out)
{
    return railsim_cli_num(PROG, opt, v, lo, hi, out);
}

int main(int argc, char **argv)
{
    mb_sim_params p = mb_sim_params_default();
    double duration = -1.0, x = 0.0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--listen")) {
            const char *c = v ? strrchr(v, ':') : NULL;
            if (!c || c == v || (size_t)(c - v) >= sizeof p.host) {
                fprintf(stderr, PROG ": --listen needs HOST:PORT, got '%s'\n", v ? v : "");
                return 2;
            }
            memcpy(p.host, v, (size_t)(c - v));
            p.host[c - v] = 0;
            bad = num(a, c + 1, 0, 65535, &x);
            p.port = (int)x;
        } else if (!strcmp(a, "--rtu")) {
            p.rtu = true;
            i--; /* takes no value */
        } else if (!strcmp(a, "--wrong-id")) {
            bad = num(a, v, 0, 1, &p.wrong_id_prob);
        } else if (!strcmp(a, "--slave")) {
            bad = num(a, v, 1, 247, &x);
            p.slave = (int)x;
        } else if (!strcmp(a, "--counts-per-mm")) {
            bad = num(a, v, 1e-3, 1e7, &p.counts_per_mm);
        } else if (!strcmp(a, "--travel")) {
            bad = num(a, v, 1e-3, 1e6, &p.travel_mm);
        } else if (!strcmp(a, "--start")) {
            bad = num(a, v, 0, 1e6, &p.start_mm);
        } else if (!strcmp(a, "--drop")) {
            bad = num(a, v, 0, 1, &p.drop_prob);
        } else if (!strcmp(a, "--garble")) {
            bad = num(a, v, 0, 1, &p.garble_prob);
        } else if (!strcmp(a, "--exception")) {
            bad = num(a, v, 0, 1, &p.exception_prob);
        } else if (!strcmp(a, "--stall")) {
            bad = num(a, v, 0, 1e6, &p.stall_at_mm);
        } else if (!strcmp(a, "--alarm-after")) {
            bad = num(a, v, 0, 1e7, &p.alarm_after_s);
        } else if (!strcmp(a, "--alarm-code")) {
            bad = num(a, v, 1, 65535, &x);
            p.alarm_code = (int)x;
        } else if (!strcmp(a, "--load")) {
            bad = num(a, v, -32768, 32767, &x);
            p.load_counts = (int)x;
        } else if (!strcmp(a, "--seed")) {
            bad = num(a, v, 0, 4294967295.0, &x);
            p.seed = (unsigned)x;
        } else if (!strcmp(a, "--duration")) {
            bad = num(a, v, 0, 1e7, &duration);
        } else {
            fprintf(stderr, PROG ": unknown option '%s'\n", a);
            usage(stderr);
            return 2;
        }
        if (bad)
            return 2;
        i++; /* every option above takes one value */
    }
    mb_sim *s = NULL;
    char why[256];
    if (mb_sim_open(&s, &p, why, sizeof why) != RAIL_OK) {
        fprintf(stderr, PROG ": %s\n", why);
        return 1;
    }
    if (p.rtu)
        printf("pty: %s\n", mb_sim_path(s));
    else
        printf("listening: %s:%d\n", p.host, mb_sim_port(s));
    fflush(stdout);
    mb_sim_run(s, duration, railsim_cli_catch_stop());
    mb_sim_close(s);
    return 0;
}
