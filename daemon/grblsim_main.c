/* grblsim_main.c: `ribbon-grblsim`, the GRBL 1.1 simulator on a pseudo-terminal (logic in
 * drivers/grbl_sim.c). Prints "pty: PATH" as its first line on stdout, optionally makes a symlink
 * to it, then serves until SIGINT/SIGTERM (the handler only sets a flag). */
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "grbl_sim.h"
#include "cli.h"

#define PROG "ribbon-grblsim"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ribbon-grblsim [options]\n"
            "  --link PATH          also make PATH a symlink to the pty\n"
            "  --axes N             number of axes, 1..3 (default 2: X compress, Y shear)\n"
            "  --travel MM          machine travel of every axis (default 200)\n"
            "  --start X[,Y[,Z]]    start positions, mm (default 0)\n"
            "  --accel MM_S2        acceleration (default 200)\n"
            "  --max-feed MM_MIN    max rate $110-$112 (default 3000)\n"
            "  --require-home       homing on ($22=1): start in alarm until $H or $X\n"
            "  --soft-limits        soft limits on ($20=1; needs --require-home)\n"
            "  --set '$N=V ...'     settings stored at power-up, e.g. '$13=1' (inches)\n"
            "  --reset-on-open      a client opening the port resets the board (Arduino DTR)\n"
            "  --reset-delay S      bootloader time from that reset to the banner (default 1)\n"
            "  --wco X[,Y[,Z]]      report work positions with this offset ($10=0 style)\n"
            "  --drop P             leave a fraction P of requests unanswered\n"
            "  --garble P           garble a fraction P of replies\n"
            "  --stall AXIS:MM      stall axis X|Y|Z at MM\n"
            "  --alarm-after S      raise an alarm S seconds after start\n"
            "  --alarm-code N       GRBL alarm number for --alarm-after (default 1)\n"
            "  --seed N             fault random seed\n"
            "  --duration S         exit after S seconds (default: run until signalled)\n");
}

static int parse_double(const char *opt, const char *v, double lo, double hi, double *out)
{
    return railsim_cli_num(PROG, opt, v, lo, hi, out);
}

/* "A[,B[,C]]": one number in [lo, hi] per axis into out[0..]; axes not named keep their value. */
static int parse_axes(const char *opt, const char *v, double lo, double hi, double *out)
{
    if (!v)
        return 1;
    char buf[128];
    snprintf(buf, sizeof buf, "%s", v);
    int bad = 0;
    char *save = NULL, *tok = strtok_r(buf, ",", &save);
    for (int k = 0; tok && k < GRBL_SIM_AXES && !bad; k++, tok = strtok_r(NULL, ",", &save))
        bad = parse_double(opt, tok, lo, hi, &out[k]);
    return bad;
}

int main(int argc, char **argv)
{
    grbl_sim_params p = grbl_sim_params_default();
    const char *link = NULL;
    double duration = -1.0, x;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--link")) {
            link = v;
            i++;
            bad = !v;
        } else if (!strcmp(a, "--axes")) {
            bad = parse_double(a, v, 1, 3, &x);
            p.n_axes = (int)x;
            i++;
        } else if (!strcmp(a, "--travel")) {
            bad = parse_double(a, v, 1, 1e5, &x);
            for (int k = 0; k < GRBL_SIM_AXES; k++)
                p.travel_mm[k] = x;
            i++;
        } else if (!strcmp(a, "--start")) {
            bad = parse_axes(a, v, 0, 1e5, p.start_mm);
            i++;
        } else if (!strcmp(a, "--wco")) {
            bad = parse_axes(a, v, -1e5, 1e5, p.wco_mm);
            p.report_wpos = v != NULL;
            i++;
        } else if (!strcmp(a, "--accel")) {
            bad = parse_double(a, v, 1e-3, 1e5, &p.accel_mm_s2);
            i++;
        } else if (!strcmp(a, "--max-feed")) {
            bad = parse_double(a, v, 1, 1e6, &p.max_feed_mm_min);
            i++;
        } else if (!strcmp(a, "--require-home")) {
            p.start_in_alarm = true;
        } else if (!strcmp(a, "--soft-limits")) {
            p.soft_limits = true;
        } else if (!strcmp(a, "--reset-on-open")) {
            p.reset_on_open = true;
        } else if (!strcmp(a, "--reset-delay")) {
            bad = parse_double(a, v, 0, 10, &p.reset_delay_s);
            i++;
        } else if (!strcmp(a, "--set")) {
            bad = !v || strlen(v) >= sizeof p.settings;
            if (!bad)
                snprintf(p.settings, sizeof p.settings, "%s", v);
            else
                fprintf(stderr, PROG ": --set needs '$N=V ...' (under %zu characters)\n", sizeof p.settings);
            i++;
        } else if (!strcmp(a, "--drop")) {
            bad = parse_double(a, v, 0, 1, &p.drop_prob);
            i++;
        } else if (!strcmp(a, "--garble")) {
            bad = parse_double(a, v, 0, 1, &p.garble_prob);
            i++;
        } else if (!strcmp(a, "--stall")) {
            if (!v || (v[0] != 'X' && v[0] != 'Y' && v[0] != 'Z') || v[1] != ':') {
                fprintf(stderr, PROG ": --stall needs AXIS:MM, e.g. X:12.5\n");
                bad = 1;
            } else {
                bad = parse_double(a, v + 2, 0, 1e5, &p.stall_at_mm[v[0] - 'X']);
            }
            i++;
        } else if (!strcmp(a, "--alarm-after")) {
            bad = parse_double(a, v, 0, 1e6, &p.alarm_after_s);
            i++;
        } else if (!strcmp(a, "--alarm-code")) {
            bad = parse_double(a, v, 1, 9, &x);
            p.alarm_code = (int)x;
            i++;
        } else if (!strcmp(a, "--seed")) {
            bad = parse_double(a, v, 0, 4294967295.0, &x);
            p.seed = (unsigned)x;
            i++;
        } else if (!strcmp(a, "--duration")) {
            bad = parse_double(a, v, 0, 1e7, &duration);
            i++;
        } else {
            fprintf(stderr, PROG ": unknown option '%s'\n", a);
            usage(stderr);
            return 2;
        }
        if (bad)
            return 2;
    }
    grbl_sim *s = NULL;
    char why[256];
    if (grbl_sim_open(&s, &p, why, sizeof why) != RAIL_OK) {
        fprintf(stderr, PROG ": %s\n", why);
        return 1;
    }
    printf("pty: %s\n", grbl_sim_path(s));
    fflush(stdout);
    if (link) {
        unlink(link);
        if (symlink(grbl_sim_path(s), link) != 0) {
            fprintf(stderr, PROG ": cannot link %s: %s\n", link, strerror(errno));
            grbl_sim_close(s);
            return 1;
        }
    }
    grbl_sim_run(s, duration, railsim_cli_catch_stop());
    if (link)
        unlink(link);
    grbl_sim_close(s);
    return 0;
}
