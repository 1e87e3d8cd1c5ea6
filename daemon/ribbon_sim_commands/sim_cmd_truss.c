/* sim_cmd_truss.c: `ribbon-sim truss`, the reduced-order truss model of the paper's section 4.
 *
 * Three modes: the two bifurcations of the symmetric branch at one L2 (default), the L2 where
 * their order switches (--find-switch), and the slow-release dynamics (--dynamics). Each prints
 * the full nonlinear model's numbers beside the paper's small-angle formulas. Text goes to
 * stdout, or one JSON object with --json; errors go to stderr and give a non-zero exit status
 * (2: bad command line, 1: the computation failed, with the reason). The program main owns
 * gsl_set_error_handler_off(); this file never aborts. */
#include "sim_cmd.h"
#include "cfg_number.h"

#include "truss.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char truss_usage[] =
    "usage: ribbon-sim truss [--lambda X] [--alpha Y] [--l2 Z] [--json]\n"
    "       ribbon-sim truss [--lambda X] [--alpha Y] --find-switch [--json]\n"
    "       ribbon-sim truss [--lambda X] [--alpha Y] [--l2 Z] --dynamics [--rate R]\n"
    "                        [--imperfection E] [--damping C] [--json]\n"
    "\n"
    "The double-mass von Mises truss of the paper's section 4, with the consistent joint-angle\n"
    "signs (theta_L + dtheta, theta_R - dtheta; DESIGN.md section 3). All quantities are\n"
    "dimensionless: mu = dl / (alpha^2 l), psi = theta / alpha, T = t sqrt(k_s / m).\n"
    "\n"
    "Default mode: follows the symmetric branch from the stable upper state while the load mu is\n"
    "released, locates the saddle-node (symmetric critical mode, turning point in mu) and the\n"
    "pitchfork (antisymmetric critical mode), and prints which comes first, with mu and psi_S at\n"
    "each, beside the small-angle formulas psi_SN = (Lambda/2)^(1/3), psi_PF = L2 (L2 + 2) / 4.\n"
    "\n"
    "  --lambda X        Lambda = 3 k_t / (alpha^2 k_s l1^2), > 0 (default 0.1)\n"
    "  --alpha Y         support rest angle alpha in rad, in (0, 0.5] (default 0.1)\n"
    "  --l2 Z            L2 = l2 / l1, > 0 (default 0.8)\n"
    "  --find-switch     instead: the L2 where the order switches, l2_switch from the full model\n"
    "                    (psi_S at the pitchfork equal to psi_S at the saddle-node) and the\n"
    "                    analytic l2_star = 2 sqrt((Lambda/2)^(1/3) + 1/4) - 1\n"
    "  --dynamics        instead: release mu from mu_start at a constant rate from rest in the\n"
    "                    upper state (gsl_odeiv2 RK8PD) and report the snap and max |psi_A|\n"
    "  --rate R          d(1 - mu)/dT for --dynamics, > 0 (default 0.001, the paper's)\n"
    "  --imperfection E  relative split of the support rest angles, |E| < 1 (default 0.001 with\n"
    "                    --dynamics; the static modes need the perfect model and refuse it)\n"
    "  --damping C       viscous damping in sqrt(k_s m) for --dynamics, >= 0 (default 0)\n"
    "  --mu-start M      load where the upper branch is picked up (default: max(1, twice the\n"
    "                    small-angle saddle-node load), doubled while the upper state is not\n"
    "                    stable there, up to a compression mu alpha^2 of 0.45)\n"
    "  --printed-signs   use the paper's printed joint angles (theta_L - dtheta, theta_R + dtheta)\n"
    "                    instead, for comparison only\n"
    "  --json            print one JSON object on stdout\n"
    "  --help            this text\n";

typedef struct truss_cli {
    truss_params p;
    int find_switch;
    int dynamics;
    int json;
    int have_imperfection;
    double rate;
    double damping;
    double mu_start; /* NAN: automatic */
} truss_cli;

static int parse_double(const char *opt, const char *s, double *out)
{
    if (s == NULL) {
        fprintf(stderr, "ribbon-sim truss: %s needs a value\n", opt);
        return -1;
    }
    char *end = NULL;
    errno = 0;
    double v = cfg_number_strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE || !isfinite(v)) {
        fprintf(stderr, "ribbon-sim truss: %s: '%s' is not a finite number\n", opt, s);
        return -1;
    }
    *out = v;
    return 0;
}

/* Returns 0 to run, 1 after --help, -1 on a bad command line. */
static int truss_cli_parse(int argc, char **argv, truss_cli *c)
{
    c->p = truss_params_default();
    c->find_switch = c->dynamics = c->json = c->have_imperfection = 0;
    c->rate = 1e-3;
    c->damping = 0.0;
    c->mu_start = NAN;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        double *target = NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(truss_usage, stdout);
            return 1;
        } else if (strcmp(a, "--json") == 0) {
            c->json = 1;
        } else if (strcmp(a, "--find-switch") == 0) {
            c->find_switch = 1;
        } else if (strcmp(a, "--dynamics") == 0) {
            c->dynamics = 1;
        } else if (strcmp(a, "--printed-signs") == 0) {
            c->p.printed_signs = 1;
        } else if (strcmp(a, "--lambda") == 0) {
            target = &c->p.lambda;
        } else if (strcmp(a, "--alpha") == 0) {
            target = &c->p.alpha;
        } else if (strcmp(a, "--l2") == 0) {
            target = &c->p.l2;
        } else if (strcmp(a, "--rate") == 0) {
            target = &c->rate;
        } else if (strcmp(a, "--imperfection") == 0) {
            target = &c->p.imperfection;
            c->have_imperfection = 1;
        } else if (strcmp(a, "--damping") == 0) {
            target = &c->damping;
        } else if (strcmp(a, "--mu-start") == 0) {
            target = &c->mu_start;
        } else {
            fprintf(stderr, "ribbon-sim truss: unknown option '%s' (see --help)\n", a);
            return -1;
        }
        if (target != NULL) {
            if (parse_double(a, v, target) != 0)
                return -1;
            i++;
        }
    }
    if (c->find_switch && c->dynamics) {
        fprintf(stderr, "ribbon-sim truss: --find-switch and --dynamics are separate modes\n");
        return -1;
    }
    if (c->dynamics && !c->have_imperfection)
        c->p.imperfection = 1e-3;
    if (!c->dynamics && c->have_imperfection && c->p.imperfection != 0.0) {
        fprintf(stderr, "ribbon-sim truss: --imperfection applies to --dynamics only (the "
                        "classification follows the symmetric branch of the perfect model)\n");
        return -1;
    }
    char msg[160];
    if (truss_params_check(&c->p, msg, sizeof msg) != TRUSS_OK) {
        fprintf(stderr, "ribbon-sim truss: %s\n", msg);
        return -1;
    }
    if (c->dynamics && !(c->rate > 0.0 && c->rate <= 1.0)) {
        fprintf(stderr, "ribbon-sim truss: --rate must be in (0, 1]\n");
        return -1;
    }
    if (!(c->damping >= 0.0)) {
        fprintf(stderr, "ribbon-sim truss: --damping must be >= 0\n");
        return -1;
    }
    if (!isnan(c->mu_start) && !(c->mu_start > 0.0 && c->mu_start <= 1e3)) {
        fprintf(stderr, "ribbon-sim truss: --mu-start must be in (0, 1000]\n");
        return -1;
    }
    return 0;
}

/* Automatic starting load: the paper's mu = 1, raised to twice the small-angle saddle-node load
 * of the smallest L2 searched (the saddle-node load falls with L2) so the upper state exists. */
static double mu_start_auto(const truss_params *p, double l2_lo)
{
    double psi_sn = truss_analytic_psi_sn(p->lambda);
    return fmax(1.0, 2.0 * truss_analytic_mu_at_psi(p->lambda, l2_lo, psi_sn));
}

static truss_cont_opts cont_opts_for(const truss_cli *c, double l2_lo)
{
    truss_cont_opts o = truss_cont_opts_default();
    o.mu_start = isnan(c->mu_start) ? mu_start_auto(&c->p, l2_lo) : c->mu_start;
    o.mu_max = fmax(o.mu_max, 20.0 * o.mu_start);
    return o;
}

/* truss_continue, and with an automatic start, retried from twice the load while the upper state
 * is not stable there (the pitchfork can lie above the paper's mu = 1), up to the compression
 * limit. */
static truss_error continue_auto(const truss_cli *c, const truss_params *p, truss_cont_opts *o,
                                 truss_branch *b)
{
    truss_error e = truss_continue(p, o, 0, b);
    for (int k = 0; k < 8 && e == TRUSS_ERR_NO_UPPER && isnan(c->mu_start); k++) {
        double next = 2.0 * o->mu_start;
        if (!(next * p->alpha * p->alpha < 0.5 * TRUSS_COMPRESSION_MAX))
            break;
        o->mu_start = next;
        o->mu_max = fmax(o->mu_max, 20.0 * next);
        e = truss_continue(p, o, 0, b);
    }
    return e;
}

/* The starting load must leave room between the supports: dl / l = mu alpha^2. */
static int check_compression(const truss_cli *c, double mu_start)
{
    double comp = mu_start * c->p.alpha * c->p.alpha;
    if (comp < TRUSS_COMPRESSION_MAX)
        return 0;
    fprintf(stderr, "ribbon-sim truss: the upper state needs mu_start = %g, a compression "
                    "dl/l = mu alpha^2 = %g, beyond the model's %g: Lambda or alpha too large "
                    "(or --mu-start too large)\n", mu_start, comp, TRUSS_COMPRESSION_MAX);
    return -1;
}

static json_t *jnum(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

static const char *regime_of(truss_event_type t)
{
    return t == TRUSS_EVENT_PITCHFORK ? "asymmetric" : t == TRUSS_EVENT_SADDLE_NODE ? "symmetric" : "none";
}

static int json_print(json_t *o)
{
    if (o == NULL) {
        fprintf(stderr, "ribbon-sim truss: out of memory building JSON\n");
        return 1;
    }
    int rc = json_dumpf(o, stdout, JSON_REAL_PRECISION(10));
    json_decref(o);
    if (rc != 0) {
        fprintf(stderr, "ribbon-sim truss: cannot write JSON to stdout\n");
        return 1;
    }
    fputc('\n', stdout);
    return 0;
}

static int fail(const char *what, truss_error e)
{
    fprintf(stderr, "ribbon-sim truss: %s: %s\n", what, truss_error_message(e));
    return 1;
}

static int run_events(const truss_cli *c)
{
    truss_cont_opts o = cont_opts_for(c, c->p.l2);
    if (check_compression(c, o.mu_start) != 0)
        return 1;
    truss_branch b;
    truss_error e = continue_auto(c, &c->p, &o, &b);
    if (e == TRUSS_ERR_NO_UPPER) {
        if (c->p.printed_signs && c->p.l2 >= 0.5)
            fprintf(stderr, "ribbon-sim truss: no stable upper state: with the printed signs the "
                            "upper state is unstable to the antisymmetric mode (small-angle "
                            "theory: at every load when L2 >= 1/2)\n");
        else
            fprintf(stderr, "ribbon-sim truss: no stable upper state at mu_start = %g (compression "
                            "too small?); try a larger --mu-start\n", o.mu_start);
        return 1;
    }
    if (e != TRUSS_OK)
        return fail("continuation of the symmetric branch", e);
    double psi_sn = truss_analytic_psi_sn(c->p.lambda);
    double psi_pf = truss_analytic_psi_pf(c->p.l2);
    double mu_sn_a = truss_analytic_mu_at_psi(c->p.lambda, c->p.l2, psi_sn);
    double mu_pf_a = truss_analytic_mu_at_psi(c->p.lambda, c->p.l2, psi_pf);
    truss_event_type first_a = psi_pf > psi_sn ? TRUSS_EVENT_PITCHFORK : TRUSS_EVENT_SADDLE_NODE;
    double l2_star = truss_analytic_l2_star(c->p.lambda);

    if (c->json) {
        json_t *root = json_object();
        json_t *sn = json_object(), *an = json_object();
        json_t *pf = b.pitchfork.found ? json_object() : json_null();
        json_object_set_new(root, "lambda", jnum(c->p.lambda));
        json_object_set_new(root, "alpha", jnum(c->p.alpha));
        json_object_set_new(root, "l2", jnum(c->p.l2));
        json_object_set_new(root, "signs", json_string(c->p.printed_signs ? "printed" : "consistent"));
        json_object_set_new(root, "mu_start", jnum(o.mu_start));
        json_object_set_new(root, "first_bifurcation", json_string(truss_event_name(b.first)));
        json_object_set_new(root, "regime", json_string(regime_of(b.first)));
        json_object_set_new(sn, "mu", jnum(b.saddle_node.at.mu));
        json_object_set_new(sn, "psi_s", jnum(b.saddle_node.at.psi_s));
        json_object_set_new(sn, "mode_parity", jnum(b.saddle_node.at.stab.mode_parity));
        json_object_set_new(sn, "load_projection", jnum(b.saddle_node.at.stab.load_projection));
        json_object_set_new(root, "saddle_node", sn);
        if (b.pitchfork.found) {
            json_object_set_new(pf, "mu", jnum(b.pitchfork.at.mu));
            json_object_set_new(pf, "psi_s", jnum(b.pitchfork.at.psi_s));
            json_object_set_new(pf, "mode_parity", jnum(b.pitchfork.at.stab.mode_parity));
            json_object_set_new(pf, "load_projection", jnum(b.pitchfork.at.stab.load_projection));
        }
        json_object_set_new(root, "pitchfork", pf);
        json_object_set_new(an, "psi_sn", jnum(psi_sn));
        json_object_set_new(an, "mu_sn", jnum(mu_sn_a));
        json_object_set_new(an, "psi_pf", jnum(psi_pf));
        json_object_set_new(an, "mu_pf", jnum(mu_pf_a));
        json_object_set_new(an, "first_bifurcation", json_string(truss_event_name(first_a)));
        json_object_set_new(an, "l2_star", jnum(l2_star));
        json_object_set_new(root, "small_angle", an);
        truss_branch_free(&b);
        return json_print(root);
    }
    printf("truss: Lambda = %g, alpha = %g, L2 = %g (%s signs)\n", c->p.lambda, c->p.alpha,
           c->p.l2, c->p.printed_signs ? "printed" : "consistent");
    printf("first bifurcation: %s (%s snap-through)\n", truss_event_name(b.first), regime_of(b.first));
    printf("saddle-node: mu = %.6f  psi_S = %.6f   small-angle: mu = %.6f  psi_S = %.6f\n",
           b.saddle_node.at.mu, b.saddle_node.at.psi_s, mu_sn_a, psi_sn);
    if (b.pitchfork.found)
        printf("pitchfork:   mu = %.6f  psi_S = %.6f   small-angle: mu = %.6f  psi_S = %.6f\n",
               b.pitchfork.at.mu, b.pitchfork.at.psi_s, mu_pf_a, psi_pf);
    else
        printf("pitchfork:   not on the symmetric branch for mu <= %g, psi_S >= %g   small-angle: "
               "mu = %.6f  psi_S = %.6f\n", o.mu_max, o.psi_min, mu_pf_a, psi_pf);
    printf("small-angle ordering switch L2* = %.6f (pitchfork first when L2 > L2*)\n", l2_star);
    truss_branch_free(&b);
    return 0;
}

static int run_switch(const truss_cli *c)
{
    double l2_star = truss_analytic_l2_star(c->p.lambda);
    double lo = 0.25 * l2_star, hi = 2.0 * l2_star + 0.5;
    truss_cont_opts o = cont_opts_for(c, lo);
    if (check_compression(c, o.mu_start) != 0)
        return 1;
    double l2_switch = 0.0;
    truss_error e = truss_switch_find(&c->p, &o, lo, hi, 1e-7, &l2_switch);
    /* as in continue_auto: an automatic start is raised while the upper state is unstable */
    for (int k = 0; k < 8 && e == TRUSS_ERR_NO_UPPER && isnan(c->mu_start); k++) {
        double next = 2.0 * o.mu_start;
        if (!(next * c->p.alpha * c->p.alpha < 0.5 * TRUSS_COMPRESSION_MAX))
            break;
        o.mu_start = next;
        o.mu_max = fmax(o.mu_max, 20.0 * next);
        e = truss_switch_find(&c->p, &o, lo, hi, 1e-7, &l2_switch);
    }
    if (e != TRUSS_OK) {
        char what[128];
        snprintf(what, sizeof what, "ordering switch between L2 = %g and %g", lo, hi);
        return fail(what, e);
    }
    if (c->json) {
        json_t *root = json_object();
        json_object_set_new(root, "lambda", jnum(c->p.lambda));
        json_object_set_new(root, "alpha", jnum(c->p.alpha));
        json_object_set_new(root, "signs", json_string(c->p.printed_signs ? "printed" : "consistent"));
        json_object_set_new(root, "l2_switch", jnum(l2_switch));
        json_object_set_new(root, "l2_star", jnum(l2_star));
        json_object_set_new(root, "search_l2_lo", jnum(lo));
        json_object_set_new(root, "search_l2_hi", jnum(hi));
        return json_print(root);
    }
    printf("truss: Lambda = %g, alpha = %g (%s signs)\n", c->p.lambda, c->p.alpha,
           c->p.printed_signs ? "printed" : "consistent");
    printf("l2_switch (full model) = %.6f\n", l2_switch);
    printf("l2_star (small-angle)  = %.6f\n", l2_star);
    printf("pitchfork first (asymmetric snap) when L2 > l2_switch, saddle-node first below\n");
    return 0;
}

static int run_dynamics(const truss_cli *c)
{
    truss_dyn_opts o = truss_dyn_opts_default();
    o.mu_rate = c->rate;
    o.damping = c->damping;
    o.mu_start = isnan(c->mu_start) ? mu_start_auto(&c->p, c->p.l2) : c->mu_start;
    if (check_compression(c, o.mu_start) != 0)
        return 1;
    truss_dyn_result r;
    truss_error e = truss_dynamics_run(&c->p, &o, 0, &r);
    if (e != TRUSS_OK)
        return fail("dynamics", e);
    if (c->json) {
        json_t *root = json_object();
        json_object_set_new(root, "lambda", jnum(c->p.lambda));
        json_object_set_new(root, "alpha", jnum(c->p.alpha));
        json_object_set_new(root, "l2", jnum(c->p.l2));
        json_object_set_new(root, "signs", json_string(c->p.printed_signs ? "printed" : "consistent"));
        json_object_set_new(root, "rate", jnum(o.mu_rate));
        json_object_set_new(root, "imperfection", jnum(c->p.imperfection));
        json_object_set_new(root, "damping", jnum(o.damping));
        json_object_set_new(root, "mu_start", jnum(o.mu_start));
        json_object_set_new(root, "snapped", json_boolean(r.snapped));
        json_object_set_new(root, "mu_snap", r.snapped ? jnum(r.mu_snap) : json_null());
        json_object_set_new(root, "t_snap", r.snapped ? jnum(r.t_snap) : json_null());
        json_object_set_new(root, "psi_a_max_before_snap", jnum(r.psi_a_max_before));
        json_object_set_new(root, "psi_a_max", jnum(r.psi_a_max));
        truss_dyn_result_free(&r);
        return json_print(root);
    }
    printf("truss dynamics: Lambda = %g, alpha = %g, L2 = %g, rate %g, imperfection %g, damping %g\n",
           c->p.lambda, c->p.alpha, c->p.l2, o.mu_rate, c->p.imperfection, o.damping);
    if (r.snapped)
        printf("snap at mu = %.6f (T = %.3f)\n", r.mu_snap, r.t_snap);
    else
        printf("no snap down to mu = %g\n", o.mu_end);
    printf("max |psi_A| before the snap = %.4g, over the run = %.4g\n", r.psi_a_max_before, r.psi_a_max);
    truss_dyn_result_free(&r);
    return 0;
}

int sim_cmd_truss(int argc, char **argv)
{
    truss_cli c;
    int rc = truss_cli_parse(argc, argv, &c);
    if (rc > 0)
        return 0;
    if (rc < 0)
        return 2;
    if (c.find_switch)
        return run_switch(&c);
    if (c.dynamics)
        return run_dynamics(&c);
    return run_events(&c);
}
