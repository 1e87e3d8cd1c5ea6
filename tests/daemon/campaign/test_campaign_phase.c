/* test_campaign_phase.c: the lab's phase diagram from a store (campaign_phase.h) and ribbonctl
 * phase / plan on it, offline. A store with specimens trialled at known regimes: the experimental
 * boundary lands in the bracket they make (phi 90: asymmetric up to 0.16, symmetric from 0.17),
 * an overlapping phi gets a probit fit with an interval over the overlap, repeated trials are
 * counts, trials without a specimen or a result do not count; the CSV's rows and the JSON;
 * the named errors for no specimens and no trials; the proposals' store (a new plan supersedes,
 * approval once); `ribbonctl phase` and `ribbonctl plan` with a predicted boundary CSV, and the
 * planner refusing a phi outside the model's range, by name. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>
#include <sqlite3.h>

#include "campaign.h"
#include "store.h"

#define OK(x) assert_int_equal((x), STORE_OK)

static char why[512];
static const double T0 = 1.8e9;

typedef struct fx {
    char dir[64], db[96], bcsv[96];
    store *st;
} fx;

static int setup(void **state)
{
    fx *f = calloc(1, sizeof *f);
    snprintf(f->dir, sizeof f->dir, "/tmp/test_campaign_phase.XXXXXX");
    if (!mkdtemp(f->dir)) return -1;
    snprintf(f->db, sizeof f->db, "%s/s.db", f->dir);
    snprintf(f->bcsv, sizeof f->bcsv, "%s/boundary.csv", f->dir);
    if (store_open(f->db, &f->st, why, sizeof why) != STORE_OK) return -1;
    /* a predicted boundary as ribbon-sim boundary writes it: phi 50 .. 130, Gamma* 0.15 .. 0.19 */
    FILE *b = fopen(f->bcsv, "w");
    if (!b) return -1;
    fprintf(b, "kind,dl,phi_deg,gamma,dw,dz,eig_even,eig_odd,parity_even,parity_odd\n");
    for (int k = 0; k <= 8; k++)
        fprintf(b, "boundary,0.5,%g,%g,0.4,0.1,0,0,1,-1\n", 50.0 + 10 * k, 0.15 + 0.005 * k);
    fprintf(b, "saddle-node,0.5,90,0.17,0.45,0.1,,,,\n");
    fclose(b);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fx *f = *state;
    store_close(f->st);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", f->dir);
    if (system(cmd) != 0) return -1;
    free(f);
    return 0;
}

static int64_t specimen(store *st, const char *name, double phi, double gamma)
{
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "%s", name);
    sp.length_m = 0.2;
    sp.width_m = 0.005;
    sp.thickness_m = 2.5e-4;
    sp.phi_deg = phi;
    sp.fold_position = gamma;
    int64_t id = 0;
    OK(store_specimen_upsert(st, &sp, &id, why, sizeof why));
    return id;
}

/* A finished trial of specimen sid measured as regime (NO_SNAP: no snap; UNKNOWN: no result). */
static void trial(store *st, int64_t sid, store_regime regime)
{
    store_trial_def d = store_trial_def_default();
    d.specimen_id = sid;
    d.created_wall_s = T0;
    int64_t id;
    OK(store_trial_create(st, &d, &id, why, sizeof why));
    OK(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, T0 + 1, why, sizeof why));
    if (regime != STORE_REGIME_UNKNOWN)
        OK(store_trial_set_result(st, id, regime != STORE_REGIME_NO_SNAP, regime == STORE_REGIME_NO_SNAP ? NAN : 0.4,
                                  regime, why, sizeof why));
    OK(store_trial_set_status(st, id, STORE_STATUS_DONE, NULL, T0 + 2, why, sizeof why));
}

/* phi 90: asymmetric at 0.15, 0.16 (twice, two specimens of one design), symmetric at 0.17,
 * 0.18 (and a no-snap at 0.18); phi 60: overlapping (0.14 asym, 0.15 asym + sym, 0.16 sym). */
static void fill(store *st)
{
    int64_t a = specimen(st, "A", 90, 0.15), b = specimen(st, "B", 90, 0.16), b2 = specimen(st, "B2", 90, 0.16),
            c = specimen(st, "C", 90, 0.17), d = specimen(st, "D", 90, 0.18);
    int64_t e = specimen(st, "E", 60, 0.14), g = specimen(st, "G", 60, 0.15), h = specimen(st, "H", 60, 0.16);
    specimen(st, "UNUSED", 120, 0.2);
    trial(st, a, STORE_REGIME_ASYMMETRIC);
    trial(st, b, STORE_REGIME_ASYMMETRIC);
    trial(st, b2, STORE_REGIME_ASYMMETRIC);
    trial(st, c, STORE_REGIME_SYMMETRIC);
    trial(st, d, STORE_REGIME_SYMMETRIC);
    trial(st, d, STORE_REGIME_NO_SNAP);
    trial(st, d, STORE_REGIME_UNKNOWN); /* no result: not counted */
    trial(st, e, STORE_REGIME_ASYMMETRIC);
    trial(st, g, STORE_REGIME_ASYMMETRIC);
    trial(st, g, STORE_REGIME_SYMMETRIC);
    trial(st, h, STORE_REGIME_SYMMETRIC);
    trial(st, 0, STORE_REGIME_SYMMETRIC); /* no specimen: not the campaign's */
}

static void named_errors(void **state)
{
    fx *f = *state;
    campaign_phase ph;
    assert_int_equal(campaign_phase_collect(f->st, &ph, why, sizeof why), -2);
    assert_non_null(strstr(why, "no specimens in the store"));
    specimen(f->st, "A", 90, 0.15);
    trial(f->st, 0, STORE_REGIME_SYMMETRIC);
    assert_int_equal(campaign_phase_collect(f->st, &ph, why, sizeof why), -2);
    assert_non_null(strstr(why, "no measured trials of any specimen"));
}

static void edges_land_in_their_brackets(void **state)
{
    fx *f = *state;
    fill(f->st);
    campaign_phase ph;
    assert_int_equal(campaign_phase_collect(f->st, &ph, why, sizeof why), 0);
    assert_int_equal(ph.n_specimens, 9);
    assert_int_equal(ph.n_trials, 10);
    assert_int_equal(ph.n_obs, 7);
    assert_int_equal(ph.n_edges, 2);
    const campaign_edge *e60 = &ph.edges[0], *e90 = &ph.edges[1];
    assert_true(e90->phi_deg == 90 && e90->method == CAMPAIGN_EDGE_BRACKET);
    assert_true(fabs(e90->lo - 0.16) < 1e-12 && fabs(e90->hi - 0.17) < 1e-12 && fabs(e90->gamma - 0.165) < 1e-12);
    assert_int_equal(e90->n_asym, 3);
    assert_int_equal(e90->n_sym, 2);
    assert_true(e60->phi_deg == 60 && e60->method == CAMPAIGN_EDGE_PROBIT);
    assert_true(e60->gamma > 0.14 && e60->gamma < 0.16 && e60->lo < 0.15 && e60->hi > 0.15);
    /* the pooled design point 90 / 0.16: two specimens, two trials */
    const campaign_obs *o = NULL;
    for (size_t k = 0; k < ph.n_obs; k++)
        if (ph.obs[k].phi_deg == 90 && ph.obs[k].gamma == 0.16) o = &ph.obs[k];
    assert_non_null(o);
    assert_int_equal(o->n_asym, 2);
    assert_int_equal(o->n_specimens, 2);

    /* The CSV, with the predicted boundary's column. */
    campaign_predicted pred;
    assert_int_equal(campaign_predicted_load_csv(f->bcsv, &pred, why, sizeof why), 0);
    assert_int_equal(pred.n, 9);
    char csv[128];
    snprintf(csv, sizeof csv, "%s/phase.csv", f->dir);
    assert_int_equal(campaign_phase_write_csv(&ph, &pred, csv, why, sizeof why), 0);
    FILE *in = fopen(csv, "r");
    assert_non_null(in);
    char line[512];
    int points = 0, edges = 0, predicted = 0, saw90 = 0, saw60 = 0, saw_point = 0;
    assert_non_null(fgets(line, sizeof line, in));
    assert_string_equal(line, "kind,phi_deg,gamma,n_asym,n_sym,n_other,n_specimens_or_points,method,lo,hi,width,"
                              "predicted_gamma\n");
    while (fgets(line, sizeof line, in)) {
        assert_null(strstr(line, "nan"));
        if (!strncmp(line, "point,", 6)) points++;
        if (!strncmp(line, "edge,", 5)) edges++;
        if (!strncmp(line, "predicted,", 10)) predicted++;
        if (!strcmp(line, "edge,90,0.165,3,2,,4,bracket,0.16,0.17,0,0.17\n")) saw90 = 1;
        if (!strncmp(line, "edge,60,", 8) && strstr(line, ",probit,") && strstr(line, ",0.155\n")) saw60 = 1;
        if (!strcmp(line, "point,90,0.18,0,1,1,1,,,,,0.17\n")) saw_point = 1;
    }
    fclose(in);
    assert_int_equal(points, 7);
    assert_int_equal(edges, 2);
    assert_int_equal(predicted, 9);
    assert_true(saw90);
    assert_true(saw60);
    assert_true(saw_point);
    /* JSON: the same numbers */
    json_t *j = campaign_phase_json(&ph, &pred);
    json_t *je = json_array_get(json_object_get(j, "edges"), 1);
    assert_string_equal(json_string_value(json_object_get(je, "method")), "bracket");
    assert_true(fabs(json_real_value(json_object_get(je, "lo")) - 0.16) < 1e-12);
    assert_int_equal(json_integer_value(json_object_get(j, "trials")), 10);
    json_decref(j);
    /* the figure */
    char png[128];
    snprintf(png, sizeof png, "%s/phase.png", f->dir);
    assert_int_equal(campaign_phase_png(&ph, &pred, NULL, png, why, sizeof why), 0);
    FILE *p = fopen(png, "rb");
    unsigned char sig[8] = {0};
    assert_non_null(p);
    assert_int_equal(fread(sig, 1, 8, p), 8);
    fclose(p);
    assert_memory_equal(sig, "\x89PNG\r\n\x1a\n", 8);
    /* interpolation and the model's range */
    double g;
    assert_int_equal(campaign_predicted_at(&pred, 95, &g, why, sizeof why), 0);
    assert_true(fabs(g - 0.1725) < 1e-12);
    assert_int_equal(campaign_predicted_at(&pred, 30, &g, why, sizeof why), -1);
    assert_non_null(strstr(why, "outside the model's range 50 .. 130 deg"));
    campaign_predicted_free(&pred);
    campaign_phase_free(&ph);
}

static void proposals_store(void **state)
{
    fx *f = *state;
    store_plan_proposal p[2] = {{.phi_deg = 90, .gamma = 0.165, .sd_before = 0.01, .predicted_gamma = 0.17,
                                 .offset_mean = -0.005, .offset_sd = 0.004, .calibrated = 1},
                                {.phi_deg = 60, .gamma = 0.15, .sd_before = 0.02, .predicted_gamma = 0.155}};
    OK(store_plan_add_batch(f->st, p, 2, T0, why, sizeof why));
    assert_true(p[0].id > 0 && p[1].id > p[0].id && p[0].batch == 1);
    store_plan_proposal q[1] = {{.phi_deg = 120, .gamma = 0.18, .sd_before = 0.02, .predicted_gamma = 0.18}};
    OK(store_plan_add_batch(f->st, q, 1, T0 + 1, why, sizeof why));
    store_plan_proposal r;
    OK(store_plan_get(f->st, p[0].id, &r, why, sizeof why));
    assert_int_equal(r.status, STORE_PLAN_SUPERSEDED);
    assert_int_equal(store_plan_approve(f->st, p[0].id, 1, 0, 1, T0, why, sizeof why), STORE_E_STATE);
    assert_non_null(strstr(why, "superseded"));
    int64_t sid = specimen(f->st, "plan-3", 120, 0.18);
    store_queue_item it = store_queue_item_default();
    it.kind = STORE_QUEUE_TRIAL;
    it.specimen_id = sid;
    int64_t qid;
    OK(store_queue_add(f->st, &it, T0, &qid, why, sizeof why));
    OK(store_plan_approve(f->st, q[0].id, sid, 0, qid, T0 + 2, why, sizeof why));
    OK(store_plan_get(f->st, q[0].id, &r, why, sizeof why));
    assert_int_equal(r.status, STORE_PLAN_APPROVED);
    assert_string_equal(r.specimen_name, "plan-3");
    assert_int_equal(store_plan_approve(f->st, q[0].id, sid, 0, qid, T0 + 3, why, sizeof why), STORE_E_STATE);
    assert_int_equal(store_plan_get(f->st, 99, &r, why, sizeof why), STORE_E_NOTFOUND);
    store_plan_proposal bad = {.phi_deg = 200, .gamma = 0.1};
    assert_int_equal(store_plan_add_batch(f->st, &bad, 1, T0, why, sizeof why), STORE_E_INVALID);
    store_plan_proposal *v;
    size_t n;
    OK(store_plan_list(f->st, &v, &n, why, sizeof why));
    assert_int_equal(n, 3);
    assert_true(v[0].id == q[0].id); /* newest first */
    free(v);
}

/* ribbonctl phase and plan on the store, offline, with the predicted boundary's CSV. */
static int run(const char *cmd, char *out, size_t len)
{
    FILE *p = popen(cmd, "r");
    if (!p) return -1;
    size_t n = fread(out, 1, len - 1, p);
    out[n] = '\0';
    int st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void ribbonctl_phase_and_plan(void **state)
{
    fx *f = *state;
    fill(f->st);
    char cmd[1024], out[8192];
    snprintf(cmd, sizeof cmd, "%s/ribbonctl phase --db %s --boundary-csv %s --csv %s/p.csv --out %s/p.png 2>&1",
             RIBBON_BIN_DIR, f->db, f->bcsv, f->dir, f->dir);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "phase figure: "));
    snprintf(cmd, sizeof cmd, "%s/ribbonctl phase --db %s --boundary-csv %s 2>&1", RIBBON_BIN_DIR, f->db, f->bcsv);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "bracket"));
    /* the planner: phi 30 is outside the model's range, named; nothing stored */
    snprintf(cmd, sizeof cmd, "%s/ribbonctl plan --db %s --boundary-csv %s --phi 30,90 2>&1", RIBBON_BIN_DIR, f->db,
             f->bcsv);
    assert_int_equal(run(cmd, out, sizeof out), 1);
    assert_non_null(strstr(out, "phi 30 deg is outside the model's range 50 .. 130 deg"));
    snprintf(cmd, sizeof cmd, "%s/ribbonctl plan --db %s --boundary-csv %s --phi 60,90,120 --count 3 --json 2>&1",
             RIBBON_BIN_DIR, f->db, f->bcsv);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    json_error_t je;
    json_t *j = json_loads(out, 0, &je);
    assert_non_null(j);
    /* phi 90's bracket says Gamma* is 0.005 below its prediction (0.17), phi 60's probit about the
     * same: the fitted offset is negative, and phi 120 (no trials yet, widest) gets a specimen
     * below its prediction 0.185 */
    assert_true(json_real_value(json_object_get(j, "offset_mean")) < -0.002);
    json_t *props = json_object_get(j, "proposals");
    assert_int_equal(json_array_size(props), 3);
    int at120 = 0;
    for (size_t k = 0; k < 3; k++) {
        json_t *p = json_array_get(props, k);
        if (json_real_value(json_object_get(p, "phi_deg")) == 120) {
            at120 = 1;
            assert_true(json_real_value(json_object_get(p, "gamma")) < 0.185);
        }
    }
    assert_true(at120);
    /* the per-phi offsets with their errors: Gamma*_j - the model there, the belief's sd; the
     * spread they were pooled with lies in its prior's range */
    double spread = json_real_value(json_object_get(j, "spread_mean"));
    assert_true(spread >= 0.003 && spread <= 0.02);
    for (size_t k = 0; k < 3; k++) {
        json_t *b = json_array_get(json_object_get(j, "beliefs"), k);
        double om = json_real_value(json_object_get(b, "offset_mean")), os = json_real_value(json_object_get(b, "offset_sd"));
        assert_true(fabs(om - (json_real_value(json_object_get(b, "mean")) -
                               json_real_value(json_object_get(b, "predicted_gamma")))) < 1e-9);
        assert_true(os > 0 && os == json_real_value(json_object_get(b, "sd")));
    }
    /* phi 90's own offset: its bracket says 0.005 below */
    assert_true(json_real_value(json_object_get(json_array_get(json_object_get(j, "beliefs"), 1), "offset_mean")) < -0.003);
    json_decref(j);
    store_plan_proposal *v;
    size_t n;
    OK(store_plan_list(f->st, &v, &n, why, sizeof why));
    assert_int_equal(n, 3);
    free(v);
    /* the table prints them */
    snprintf(cmd, sizeof cmd, "%s/ribbonctl plan --db %s --boundary-csv %s --phi 60,90,120 --count 1 2>&1",
             RIBBON_BIN_DIR, f->db, f->bcsv);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "the per-phi offsets' spread"));
    assert_non_null(strstr(out, "offset +- sd"));
}

/* Trial id's calibration as the trial stores it (trial_calibrated_json's form). */
static void calibrated(store *st, int64_t id, double angle, double se, double hinge)
{
    char fit[1024];
    int n = snprintf(fit, sizeof fit,
                     "{\"ok\":true,\"parameters\":["
                     "{\"key\":\"folds.angle_left_deg\",\"scene\":-90,\"fitted\":%g,\"se\":%g,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
                     "{\"key\":\"folds.angle_right_deg\",\"scene\":-90,\"fitted\":%g,\"se\":%g,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0}",
                     angle, se, angle, se);
    if (hinge > 0)
        n += snprintf(fit + n, sizeof fit - (size_t)n,
                      ",{\"key\":\"folds.hinge_stiffness\",\"scene\":0.003,\"fitted\":%g,\"se\":0.2,\"se_kind\":\"relative\",\"determined\":true,\"at_bound\":0}",
                      hinge);
    snprintf(fit + n, sizeof fit - (size_t)n, "]}");
    store_calibrated c = {.snap_dw = 0.4, .snap_sd = 0.01, .p_other = 0.01, .regime = "asymmetric", .fit_json = fit};
    OK(store_trial_set_calibrated(st, id, &c, why, sizeof why));
}

/* ribbonctl plan from the lab strip: trials 1 (specimen A, designed at 90) and 8 (E, at 60) have
 * fits whose creases are 80 and 50 deg (relaxed 10, se 1 and 2: pooled 10 +- 1 / sqrt(1.25)), and
 * 8 a hinge too, which with --boundary-csv alone cannot be traced (said; the relaxation is used).
 * The lab strip's boundary at phi 90 is the curve's at 80: 0.165 (the scene's 0.17); with
 * --no-strip the scene's. A failed fit is counted, not pooled. */
static void ribbonctl_plan_uses_the_lab_strip(void **state)
{
    fx *f = *state;
    fill(f->st);
    calibrated(f->st, 1, -80, 1, 0);
    calibrated(f->st, 8, -50, 2, 4e-3);
    store_calibrated failed = {.failure = "at_bound: at bound: folds.angle_left_deg"};
    OK(store_trial_set_calibrated(f->st, 2, &failed, why, sizeof why));
    char cmd[1024], out[8192];
    snprintf(cmd, sizeof cmd, "%s/ribbonctl plan --db %s --boundary-csv %s --phi 60,90,120 --count 1 --json",
             RIBBON_BIN_DIR, f->db, f->bcsv);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    json_t *j = json_loads(out, 0, NULL);
    assert_non_null(j);
    json_t *strip = json_object_get(j, "strip");
    assert_int_equal(json_integer_value(json_object_get(strip, "fits")), 2);
    assert_true(fabs(json_real_value(json_object_get(strip, "relax_deg")) - 10) < 1e-9);
    assert_true(fabs(json_real_value(json_object_get(strip, "relax_se")) - 1 / sqrt(1.25)) < 1e-9);
    assert_true(json_is_null(json_object_get(strip, "hinge")));
    const char *note = json_string_value(json_object_get(strip, "note"));
    assert_non_null(strstr(note, "from 2 trial fits (no specimen calibration) (1 more trial whose fit failed"));
    assert_non_null(strstr(note, "hinge=4.00e-03 youngs=scene not used: no scene to trace it from"));
    json_t *b90 = json_array_get(json_object_get(j, "beliefs"), 1);
    assert_true(fabs(json_real_value(json_object_get(b90, "predicted_gamma")) - 0.165) < 1e-9);
    assert_true(fabs(json_real_value(json_object_get(b90, "scene_gamma")) - 0.17) < 1e-9);
    json_decref(j);
    snprintf(cmd, sizeof cmd, "%s/ribbonctl plan --db %s --boundary-csv %s --phi 60,90,120 --count 1 --no-strip --json",
             RIBBON_BIN_DIR, f->db, f->bcsv);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    j = json_loads(out, 0, NULL);
    assert_non_null(j);
    b90 = json_array_get(json_object_get(j, "beliefs"), 1);
    assert_true(fabs(json_real_value(json_object_get(b90, "predicted_gamma")) - 0.17) < 1e-9);
    assert_int_equal(json_integer_value(json_object_get(json_object_get(j, "strip"), "fits")), 0);
    json_decref(j);
    snprintf(cmd, sizeof cmd, "%s/ribbonctl plan --db %s --boundary-csv %s --phi 60,90,120 --count 1 2>&1",
             RIBBON_BIN_DIR, f->db, f->bcsv);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "strip: creases relaxed 10.00 +- 0.89 deg (2 fits), hinge the scene's"));
    assert_non_null(strstr(out, "90       0.1700     0.1650"));

    /* Specimen A (trial 1) calibrated: its calibration (relaxed 6, se 1) stands for trial
     * 1's fit; E's trial 8 still counts by its own (relaxed 10, se 2). Pooled: (6 + 10 / 4) / 1.25
     * = 6.8, chi2 0.8^2 + 3.2^2 / 4 = 3.2 over 1, se sqrt(3.2) / sqrt(1.25) = 1.6; the boundary
     * at phi 90 read at 83.2: 0.1666. */
    store_specimen a;
    OK(store_specimen_get_by_name(f->st, "A", &a, why, sizeof why));
    OK(store_specimen_set_calibration(
        f->st, a.id,
        "{\"after_trial\":1,\"trials\":[1],\"parameters\":["
        "{\"key\":\"folds.angle_left_deg\",\"start\":-90,\"value\":-84,\"se\":1,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
        "{\"key\":\"folds.angle_right_deg\",\"start\":-90,\"value\":-84,\"se\":1,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0}]}",
        NULL, why, sizeof why));
    snprintf(cmd, sizeof cmd, "%s/ribbonctl plan --db %s --boundary-csv %s --phi 60,90,120 --count 1 --json",
             RIBBON_BIN_DIR, f->db, f->bcsv);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    j = json_loads(out, 0, NULL);
    assert_non_null(j);
    strip = json_object_get(j, "strip");
    assert_int_equal(json_integer_value(json_object_get(strip, "fits")), 2);
    assert_int_equal(json_integer_value(json_object_get(strip, "calibrations")), 1);
    assert_true(fabs(json_real_value(json_object_get(strip, "relax_deg")) - 6.8) < 1e-9);
    assert_true(fabs(json_real_value(json_object_get(strip, "relax_se")) - 1.6) < 1e-9);
    note = json_string_value(json_object_get(strip, "note"));
    assert_non_null(strstr(note, "from 1 specimen calibration and 1 trial fit (of specimens without one)"));
    b90 = json_array_get(json_object_get(j, "beliefs"), 1);
    assert_true(fabs(json_real_value(json_object_get(b90, "predicted_gamma")) - (0.165 + 0.005 * 0.32)) < 1e-9);
    json_decref(j);
}

static int no_trial(void *user, const store_specimen *sp, const char *const *set, int n_set, const char *note,
                    int64_t *trial_id, char *w, size_t wl)
{
    (void)user, (void)sp, (void)set, (void)n_set, (void)note, (void)trial_id;
    snprintf(w, wl, "no trials in this test");
    return -1;
}

static int none_running(void *user, int64_t trial_id)
{
    (void)user, (void)trial_id;
    return 0;
}

/* The routes, as ribbond serves them: GET /campaign/phase (empty, saying why, on an empty store; then the
 * data with the predicted boundary from the rig's cache), GET /plan, POST /plan/ID/approve (the
 * specimen, an operator step and a trial queued; approving twice is a 409; no queue is a 409). */
static void api_routes(void **state)
{
    fx *f = *state;
    campaign_ctx c = {.st = f->st, .defaults = store_specimen_default()};
    c.defaults.length_m = 0.2, c.defaults.width_m = 0.005, c.defaults.thickness_m = 2.5e-4;
    json_t *out = NULL;
    int http = 0;
    assert_int_equal(campaign_route(&c, "GET", "/campaign/phase", NULL, &out, &http, why, sizeof why), 0);
    assert_int_equal(http, 200);
    assert_non_null(strstr(json_string_value(json_object_get(out, "empty")), "no specimens"));
    assert_int_equal(json_array_size(json_object_get(out, "edges")), 0);
    json_decref(out);
    fill(f->st);
    /* the predicted boundary from a cache file already there (its key: these two paths' texts) */
    char cache[128];
    snprintf(cache, sizeof cache, "%s/cache.csv", f->dir);
    campaign_predicted pred;
    assert_int_equal(campaign_predicted_load_csv(f->bcsv, &pred, why, sizeof why), 0);
    char *key = campaign_predicted_key_text(f->bcsv, f->bcsv);
    char line[160];
    snprintf(line, sizeof line, "# campaign-boundary key=%016llx phi=%g:%g",
             (unsigned long long)campaign_predicted_key(key), CAMPAIGN_PHI_TRACE_LO, CAMPAIGN_PHI_TRACE_HI);
    free(key);
    assert_int_equal(campaign_predicted_save_csv(&pred, cache, line, why, sizeof why), 0);
    campaign_predicted_free(&pred);
    rod_scene sc = rod_scene_default();
    c.scene = &sc;
    c.rig_path = c.scene_path = f->bcsv;
    c.boundary_cache = cache;
    assert_int_equal(campaign_route(&c, "GET", "/campaign/phase", NULL, &out, &http, why, sizeof why), 0);
    assert_int_equal(http, 200);
    json_t *pj = json_object_get(out, "predicted");
    assert_non_null(strstr(json_string_value(json_object_get(pj, "source")), "cache"));
    assert_int_equal(json_array_size(json_object_get(pj, "gamma")), 9);
    assert_int_equal(json_array_size(json_object_get(out, "edges")), 2);
    json_decref(out);
    store_plan_proposal p = {.phi_deg = 120, .gamma = 0.18, .sd_before = 0.01, .predicted_gamma = 0.185};
    assert_int_equal(store_plan_add_batch(f->st, &p, 1, T0, why, sizeof why), STORE_OK);
    char path[64];
    snprintf(path, sizeof path, "/plan/%lld/approve", (long long)p.id);
    json_t *body = json_object();
    assert_int_equal(campaign_route(&c, "POST", path, body, &out, &http, why, sizeof why), -1);
    assert_int_equal(http, 409); /* no queue */
    campaign_queue_ops ops = {.start_trial = no_trial, .trial_running = none_running};
    assert_int_equal(campaign_queue_open(f->db, &ops, NULL, NULL, &c.q, why, sizeof why), 0);
    assert_int_equal(campaign_route(&c, "POST", path, body, &out, &http, why, sizeof why), 0);
    assert_int_equal(http, 201);
    json_t *jp = json_object_get(out, "proposal");
    assert_string_equal(json_string_value(json_object_get(jp, "status")), "approved");
    char want[32];
    snprintf(want, sizeof want, "plan-%lld", (long long)p.id);
    assert_string_equal(json_string_value(json_object_get(jp, "specimen")), want);
    json_int_t op = json_integer_value(json_object_get(jp, "operator_item")),
               ti = json_integer_value(json_object_get(jp, "trial_item"));
    json_decref(out);
    store_queue_item it;
    assert_int_equal(store_queue_get(f->st, op, &it, why, sizeof why), STORE_OK);
    assert_int_equal(it.kind, STORE_QUEUE_OPERATOR);
    assert_non_null(strstr(it.prompt, "phi 120 deg, Gamma 0.1800"));
    assert_int_equal(store_queue_get(f->st, ti, &it, why, sizeof why), STORE_OK);
    assert_int_equal(it.kind, STORE_QUEUE_TRIAL);
    assert_string_equal(it.specimen_name, want);
    store_specimen sp;
    assert_int_equal(store_specimen_get_by_name(f->st, want, &sp, why, sizeof why), STORE_OK);
    assert_true(sp.phi_deg == 120 && sp.fold_position == 0.18);
    assert_int_equal(campaign_route(&c, "POST", path, body, &out, &http, why, sizeof why), -1);
    assert_int_equal(http, 409);
    assert_non_null(strstr(why, "is approved"));
    assert_int_equal(campaign_route(&c, "GET", "/plan", NULL, &out, &http, why, sizeof why), 0);
    assert_int_equal(json_array_size(out), 1);
    json_decref(out);
    assert_int_equal(campaign_route(&c, "POST", "/plan/7/reject", body, &out, &http, why, sizeof why), -1);
    assert_int_equal(http, 404);
    json_decref(body);
    campaign_queue_close(c.q);
}

/* `ribbonctl plan` (another process, another connection) writes a new plan between approval's
 * look at the proposal and its update: the proposal is superseded. The approval is refused (409,
 * STORE_E_STATE), not reported done with the proposal superseded, and the route leaves nothing of
 * it in the queue. The race is made exact: a trace callback on the approving connection writes the
 * new plan on a second one when the Nth read of one proposal has finished. */
typedef struct race {
    store *other;
    int reads, at;
} race;

static int race_cb(unsigned type, void *ctx, void *p, void *x)
{
    (void)type, (void)x;
    race *r = ctx;
    const char *sql = sqlite3_sql((sqlite3_stmt *)p);
    if (!sql || !strstr(sql, "FROM plan_proposals p") || !strstr(sql, "WHERE p.id")) return 0;
    if (++r->reads == r->at) {
        store_plan_proposal q = {.phi_deg = 60, .gamma = 0.2, .sd_before = 0.01, .predicted_gamma = 0.2};
        char w[256];
        assert_int_equal(store_plan_add_batch(r->other, &q, 1, T0 + 60, w, sizeof w), STORE_OK);
    }
    return 0;
}

static void approve_raced_by_a_new_plan(void **state)
{
    fx *f = *state;
    race r = {0};
    OK(store_open(f->db, &r.other, why, sizeof why));
    int64_t sid = specimen(f->st, "s1", 120, 0.18);
    store_plan_proposal p = {.phi_deg = 120, .gamma = 0.18, .sd_before = 0.01, .predicted_gamma = 0.185};
    OK(store_plan_add_batch(f->st, &p, 1, T0, why, sizeof why));
    r.at = 1;
    sqlite3_trace_v2(store_handle(f->st), SQLITE_TRACE_PROFILE, race_cb, &r);
    assert_int_equal(store_plan_approve(f->st, p.id, sid, 0, 1, T0 + 120, why, sizeof why), STORE_E_STATE);
    assert_non_null(strstr(why, "superseded"));
    store_plan_proposal g;
    OK(store_plan_get(f->st, p.id, &g, why, sizeof why));
    assert_int_equal(g.status, STORE_PLAN_SUPERSEDED);

    /* through the route: the new plan lands between the route's look at the proposal and the
     * approval's transaction (inside it, BEGIN IMMEDIATE keeps other writers out) */
    store_plan_proposal p2 = {.phi_deg = 100, .gamma = 0.17, .sd_before = 0.01, .predicted_gamma = 0.17};
    OK(store_plan_add_batch(f->st, &p2, 1, T0 + 180, why, sizeof why));
    campaign_ctx c = {.st = f->st, .defaults = store_specimen_default()};
    c.defaults.length_m = 0.2, c.defaults.width_m = 0.005, c.defaults.thickness_m = 2.5e-4;
    campaign_queue_ops ops = {.start_trial = no_trial, .trial_running = none_running};
    assert_int_equal(campaign_queue_open(f->db, &ops, NULL, NULL, &c.q, why, sizeof why), 0);
    r.reads = 0;
    r.at = 1;
    char path[64];
    snprintf(path, sizeof path, "/plan/%lld/approve", (long long)p2.id);
    json_t *body = json_object(), *out = NULL;
    int http = 0;
    int rc = campaign_route(&c, "POST", path, body, &out, &http, why, sizeof why);
    sqlite3_trace_v2(store_handle(f->st), 0, NULL, NULL);
    printf("approval raced: %d %d %s\n", rc, http, rc ? why : "(done)");
    assert_int_equal(rc, -1);
    assert_int_equal(http, 409);
    json_decref(out);
    json_decref(body);
    OK(store_plan_get(f->st, p2.id, &g, why, sizeof why));
    assert_int_equal(g.status, STORE_PLAN_SUPERSEDED);
    store_queue_item *v = NULL;
    size_t n = 0;
    OK(store_queue_list(f->st, &v, &n, why, sizeof why));
    for (size_t k = 0; k < n; k++) /* nothing of the refused approval waits in the queue */
        if (v[k].status == STORE_QUEUE_QUEUED) fail_msg("queue item %lld still queued", (long long)v[k].id);
    free(v);
    campaign_queue_close(c.q);
    store_close(r.other);
}

/* ribbond's --set may change the scene its files give (protocol.compression=...): the boundary
 * cache ribbonctl phase / plan wrote for the files alone is not the daemon's scene's, so the API
 * does not take it. Here the scene cannot be traced (nodes = 1, refused at once): without the
 * overrides in the key the route would serve the files' cache as this scene's boundary. */
static void cache_keyed_on_daemon_sets(void **state)
{
    fx *f = *state;
    fill(f->st);
    char cache[128];
    snprintf(cache, sizeof cache, "%s/cache.csv", f->dir);
    campaign_predicted pred;
    assert_int_equal(campaign_predicted_load_csv(f->bcsv, &pred, why, sizeof why), 0);
    char *key = campaign_predicted_key_text(f->bcsv, f->bcsv);
    char line[160];
    snprintf(line, sizeof line, "# campaign-boundary key=%016llx phi=%g:%g",
             (unsigned long long)campaign_predicted_key(key), CAMPAIGN_PHI_TRACE_LO, CAMPAIGN_PHI_TRACE_HI);
    free(key);
    assert_int_equal(campaign_predicted_save_csv(&pred, cache, line, why, sizeof why), 0);
    campaign_predicted_free(&pred);
    rod_scene sc = rod_scene_default();
    sc.nodes = 1;
    campaign_ctx c = {.st = f->st, .defaults = store_specimen_default()};
    c.scene = &sc;
    c.rig_path = c.scene_path = f->bcsv;
    c.boundary_cache = cache;
    json_t *out = NULL;
    int http = 0;
    /* the files alone: the cache is theirs */
    assert_int_equal(campaign_route(&c, "GET", "/campaign/phase", NULL, &out, &http, why, sizeof why), 0);
    assert_non_null(strstr(json_string_value(json_object_get(json_object_get(out, "predicted"), "source")), "cache"));
    json_decref(out);
    const char *sets[] = {"protocol.compression=0.3"};
    c.sets = sets;
    c.n_sets = 1;
    assert_int_equal(campaign_route(&c, "GET", "/campaign/phase", NULL, &out, &http, why, sizeof why), 0);
    assert_int_equal(http, 200);
    json_t *pj = json_object_get(out, "predicted");
    if (!json_is_null(pj))
        fail_msg("the files' cache served for a scene the daemon's --set changed: %s",
                 json_string_value(json_object_get(pj, "source")));
    printf("predicted_error: %s\n", json_string_value(json_object_get(out, "predicted_error")));
    json_decref(out);
}

/* The boundary cache is written by ribbond (GET /campaign/phase) and ribbonctl phase / plan, maybe
 * at once: two processes each save their own boundary 300 times to the same path. Every save
 * succeeds and the file left is whole, one writer's (a temp name both share: one's rename finds
 * its temp gone, or the two writes interleave in it). */
static void fill_pred(campaign_predicted *p, size_t n, double g0)
{
    memset(p, 0, sizeof *p);
    p->n = n;
    p->dl = 0.1;
    p->phi_deg = calloc(n, sizeof *p->phi_deg);
    p->gamma = calloc(n, sizeof *p->gamma);
    for (size_t k = 0; k < n; k++) p->phi_deg[k] = 30.0 + (double)k, p->gamma[k] = g0 + 1e-4 * (double)k;
}

static void cache_two_writers(void **state)
{
    fx *f = *state;
    char cache[128];
    snprintf(cache, sizeof cache, "%s/s.db.boundary.csv", f->dir);
    const size_t n[2] = {40, 90};
    const double g0[2] = {0.1, 0.2};
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    int me = pid == 0;
    campaign_predicted p;
    fill_pred(&p, n[me], g0[me]);
    int failed = 0;
    char w[300] = "";
    for (int i = 0; i < 300; i++)
        if (campaign_predicted_save_csv(&p, cache, "# campaign-boundary key=0000000000000001 phi=1:179", w, sizeof w))
            failed++;
    campaign_predicted_free(&p);
    if (me) _exit(failed ? 1 : 0);
    int st = 0;
    waitpid(pid, &st, 0);
    if (failed) fail_msg("%d of 300 saves failed here: %s", failed, w);
    assert_true(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    campaign_predicted q;
    assert_int_equal(campaign_predicted_load_csv(cache, &q, why, sizeof why), 0);
    int k = q.n == n[1];
    assert_int_equal(q.n, n[k]);
    for (size_t j = 0; j < q.n; j++) {
        assert_true(q.phi_deg[j] == 30.0 + (double)j);
        assert_true(fabs(q.gamma[j] - (g0[k] + 1e-4 * (double)j)) < 1e-15);
    }
    campaign_predicted_free(&q);
    char cmd[200];
    snprintf(cmd, sizeof cmd, "test $(ls -A %s | grep -c s.db.boundary) -eq 1", f->dir); /* no temp left behind */
    assert_int_equal(system(cmd), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(named_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(edges_land_in_their_brackets, setup, teardown),
        cmocka_unit_test_setup_teardown(proposals_store, setup, teardown),
        cmocka_unit_test_setup_teardown(ribbonctl_phase_and_plan, setup, teardown),
        cmocka_unit_test_setup_teardown(ribbonctl_plan_uses_the_lab_strip, setup, teardown),
        cmocka_unit_test_setup_teardown(api_routes, setup, teardown),
        cmocka_unit_test_setup_teardown(cache_two_writers, setup, teardown),
        cmocka_unit_test_setup_teardown(cache_keyed_on_daemon_sets, setup, teardown),
        cmocka_unit_test_setup_teardown(approve_raced_by_a_new_plan, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
