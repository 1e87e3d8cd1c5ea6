/* test_ctl_calibrate_joint.c: `ribbonctl calibrate ID ... --share-hinge` (daemon/ribbonctl_commands/
 * ctl_calibrate_joint.c, issue 32 C) run as a program on a store built here with the store's own
 * API: trials of two specimens of different widths cut from one sheet, with one hinge stiffness
 * per unit width k / b = 1.0 N/rad. S-5 is the PET scene (5 mm x 0.25 mm, creases at 86 and
 * 89.5 deg, k = 5e-3 N m/rad); S-10 the same scene with the overrides stored in its config text
 * (10 mm x 0.3 mm, creases at 0.2, at 88 and 92.5 deg, k = 1e-2). Their frames are the model's
 * equilibria (N = 31, noise-free) among frames that must be left out; the trials' predictions say
 * -88 / -90 and -90 / -90 deg and k / b 0.7. Checked: the trials are grouped per specimen, k / b
 * comes back to 1e-3 and every angle to 1e-3 deg, one scene per specimen is written and reads back
 * with its own k, the text names the shared k / b, each specimen's keys and its calibrated snap
 * beside each trial's; refusals with a reason: different specimens without --share-hinge (which
 * names the flag), a rigid hinge, per-crease hinges, a trial that is not there; and two specimens
 * whose trials' scenes are rigid with sim.fit_hinge in their rig file fitted from that guess (the
 * in-trial fit's setup), k / b back to 1%; and two specimens whose trials' rig file names
 * sim.fit_keys fitted with those keys (as one strip is), specimens naming different keys refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rod_fit.h"
#include "scene_file.h"
#include "store.h"

#define SCENE RIBBON_SOURCE_DIR "/config/scenes/pet-200x5.ini"

static char dir[64], db[128];

typedef struct run_out {
    int status;
    char out[65536];
    char err[4096];
} run_out;

static void slurp(const char *path, char *buf, size_t len)
{
    FILE *f = fopen(path, "r");
    size_t n = f ? fread(buf, 1, len - 1, f) : 0;
    buf[n] = '\0';
    if (f) fclose(f);
}

static void run(run_out *r, const char *args)
{
    char cmd[2048], o[160], e[160];
    snprintf(o, sizeof o, "%s/out.txt", dir);
    snprintf(e, sizeof e, "%s/err.txt", dir);
    snprintf(cmd, sizeof cmd, "%s calibrate %s --db %s >%s 2>%s", RIBBONCTL_PATH, args, db, o, e);
    int st = system(cmd);
    r->status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    slurp(o, r->out, sizeof r->out);
    slurp(e, r->err, sizeof r->err);
    printf("$ ribbonctl calibrate %s\nexit %d\n--- stdout\n%s--- stderr\n%s", args, r->status, r->out, r->err);
}

/* ribbonctl calibrate ARGS with --json that must succeed: its parsed output (the caller frees). */
static json_t *run_json(const char *args)
{
    run_out r;
    run(&r, args);
    assert_int_equal(r.status, 0);
    json_t *j = json_loads(r.out, 0, NULL);
    assert_non_null(j);
    return j;
}

static void frame(store_samples *w, double t, double dl, double dw, double dz, double a)
{
    store_sample s = store_sample_default();
    char why[256];
    s.t_s = t;
    s.kind = STORE_SAMPLE_FRAME;
    s.frame = (int64_t)(t * 30.0);
    s.dl = dl;
    s.dw = dw;
    s.dz = dz;
    s.a = a;
    s.quality = 1.0;
    assert_int_equal(store_samples_add(w, &s, why, sizeof why), STORE_OK);
    store_sample r = store_sample_default(); /* a rail reading beside it: no Delta Z */
    r.t_s = t + 0.001;
    r.dl = dl;
    r.dw = dw;
    assert_int_equal(store_samples_add(w, &r, why, sizeof why), STORE_OK);
}

static void event(store *st, int64_t id, double t, const char *msg)
{
    store_event e;
    memset(&e, 0, sizeof e);
    e.trial_id = id;
    e.t_s = t;
    e.wall_s = store_wall_now();
    e.kind = STORE_EVENT_STATE;
    snprintf(e.message, sizeof e.message, "%s", msg);
    char why[256];
    assert_int_equal(store_event_append(st, &e, why, sizeof why), STORE_OK);
}

/* A specimen: its name, the scene overrides of its strip (stored in its trials' config text),
   the truth's crease angles and hinge, and what its trials' prediction says. */
typedef struct spec_def {
    const char *name;
    const char *overrides_json; /* the config text's overrides line */
    const char *sets[3];        /* the same, for the truth's scene */
    int nsets;
    double width, position, truth_left, truth_right, truth_k, pred_left, pred_right, pred_k;
    const char *sim; /* the rig file's [sim] section in its trials' config text (NULL: none) */
} spec_def;

static const spec_def S5 = {"S-5", "[]", {NULL}, 0, 0.005, 0.21, -86.0, -89.5, 5e-3, -88.0, -90.0, 3.5e-3, NULL};
static const spec_def S10 = {"S-10", "[\"ribbon.width=0.01\",\"ribbon.thickness=0.3e-3\",\"folds.position=0.2\"]",
                             {"ribbon.width=0.01", "ribbon.thickness=0.3e-3", "folds.position=0.2"}, 3, 0.010, 0.2,
                             -88.0, -92.5, 1e-2, -90.0, -90.0, 7e-3, NULL};

/* The truth strip's camera observables at the given states. */
static void truth(const spec_def *s, rod_fit_obs *obs, int n)
{
    cfg_error err;
    rod_scene t;
    char a[64], b[64], k[64];
    snprintf(a, sizeof a, "folds.angle_left_deg=%g", s->truth_left);
    snprintf(b, sizeof b, "folds.angle_right_deg=%g", s->truth_right);
    snprintf(k, sizeof k, "folds.hinge_stiffness=%g", s->truth_k);
    const char *sets[8] = {"mesh.nodes=31", a, b, k};
    int ns = 4;
    for (int i = 0; i < s->nsets; i++) sets[ns++] = s->sets[i];
    assert_int_equal(cfg_scene_load(SCENE, sets, ns, &t, &err), 0);
    assert_true(fabs(t.width - s->width) < 1e-15);
    rod_fit_model *m = NULL;
    char why[256];
    assert_int_equal(rod_fit_model_alloc(&t, obs, n, 0, &m, why, sizeof why), ROD_OK);
    double u[ROD_FIT_NKEYS], y[256];
    rod_fit_scene_values(&t, u);
    assert_int_equal(rod_fit_model_eval(m, u, NULL, y, NULL, why, sizeof why), ROD_OK);
    rod_fit_model_free(m);
    for (int i = 0; i < n; i++) {
        obs[i].dz = y[2 * i];
        obs[i].a = y[2 * i + 1];
    }
}

/* The rigid-creased pair of the hinge guess's case: the same strips, their trials' scenes with
   rigid creases (a stored override) and no hinge in the prediction's record. */
static const spec_def S5R = {"S-5r", "[\"folds.hinge_stiffness=rigid\"]", {NULL}, 0, 0.005, 0.21, -86.0, -89.5, 5e-3,
                             -88.0, -90.0, NAN, NULL};
static const spec_def S10R = {"S-10r",
                              "[\"ribbon.width=0.01\",\"ribbon.thickness=0.3e-3\",\"folds.position=0.2\","
                              "\"folds.hinge_stiffness=rigid\"]",
                              {"ribbon.width=0.01", "ribbon.thickness=0.3e-3", "folds.position=0.2"}, 3, 0.010, 0.2,
                              -88.0, -92.5, 1e-2, -90.0, -90.0, NAN, NULL};
#define FIT_HINGE 3.5e-3 /* the rig file's sim.fit_hinge in the rigid pair's trials */

/* The stored-keys pair: the same strips with their right creases at the predictions' -90 deg, their
   trials' rig file naming sim.fit_keys = folds.angle_left_deg (S-5k, S-10k); S-10j names the
   right angle instead. */
static const spec_def S5K = {"S-5k", "[]", {NULL}, 0, 0.005, 0.21, -86.0, -90.0, 5e-3, -88.0, -90.0, 3.5e-3,
                             "[sim]\nfit_keys = folds.angle_left_deg\n"};
static const spec_def S10K = {"S-10k", "[\"ribbon.width=0.01\",\"ribbon.thickness=0.3e-3\",\"folds.position=0.2\"]",
                              {"ribbon.width=0.01", "ribbon.thickness=0.3e-3", "folds.position=0.2"}, 3, 0.010, 0.2,
                              -88.0, -90.0, 1e-2, -90.0, -90.0, 7e-3, "[sim]\nfit_keys = folds.angle_left_deg\n"};
static const spec_def S10J = {"S-10j", "[\"ribbon.width=0.01\",\"ribbon.thickness=0.3e-3\",\"folds.position=0.2\"]",
                              {"ribbon.width=0.01", "ribbon.thickness=0.3e-3", "folds.position=0.2"}, 3, 0.010, 0.2,
                              -88.0, -90.0, 1e-2, -90.0, -90.0, 7e-3, "[sim]\nfit_keys = folds.angle_right_deg\n"};

static char *config_text(const spec_def *s)
{
    FILE *f = fopen(SCENE, "r");
    assert_non_null(f);
    static char text[16384];
    int rigid = s == &S5R || s == &S10R;
    int n = snprintf(text, sizeof text, "# rig file /lab/rig.ini\n[rig]\nmode = mock\nscene = pet.ini\n%s# scene file %s\n",
                     rigid ? "[sim]\nfit_hinge = 3.5e-3\n" : s->sim ? s->sim : "", SCENE);
    n += (int)fread(text + n, 1, sizeof text - (size_t)n - 512, f);
    fclose(f);
    snprintf(text + n, sizeof text - (size_t)n, "# overrides applied in order after the files: %s\n# note: joint test\n",
             s->overrides_json);
    return text;
}

enum { WITH_SHEAR = 1, LOWER = 2 };

/* A finished trial of specimen s: the truth's frames (dz negated: the lower state) and frames to
   be left out. */
static int64_t add_trial(store *st, const spec_def *s, int parts)
{
    char why[256];
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "%s", s->name);
    sp.length_m = 0.2;
    sp.width_m = s->width;
    sp.thickness_m = 0.25e-3;
    int64_t spid = 0;
    assert_int_equal(store_specimen_upsert(st, &sp, &spid, why, sizeof why), STORE_OK);
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_MOCK;
    d.config_text = config_text(s);
    d.specimen_id = spid;
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &d, &id, why, sizeof why), STORE_OK);
    store_prediction p = store_prediction_default();
    p.trial_id = id;
    snprintf(p.scene_hash, sizeof p.scene_hash, "test");
    p.snapped = true;
    p.snap_dw = 0.21;
    p.regime = STORE_REGIME_SYMMETRIC;
    p.nodes = 101;
    p.dt = 1e-3;
    p.imperfection = 1e-6;
    p.wall_s = 1.0;
    p.creases.angle_deg[0] = s->pred_left;
    p.creases.angle_deg[1] = s->pred_right;
    p.creases.angle_from[0] = p.creases.angle_from[1] = STORE_SOURCE_SPECIMEN;
    p.creases.position[0] = s->position;
    p.creases.position[1] = 1.0 - s->position;
    p.creases.position_from[0] = p.creases.position_from[1] = STORE_SOURCE_SCENE;
    p.creases.hinge_stiffness = s->pred_k;
    double t[2] = {0, 1}, dw[2] = {0, 0.21}, z[2] = {0.3, 0.3};
    p.curve = (store_curve){2, t, dw, z, z};
    assert_int_equal(store_prediction_insert(st, &p, NULL, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, store_wall_now(), why, sizeof why),
                     STORE_OK);
    rod_fit_obs obs[32];
    int n = 0;
    for (int k = 0; k < 6; k++) obs[n++] = (rod_fit_obs){0.25 + 0.01 * k, 0.0, 0, 0};
    int nc = n;
    if (parts & WITH_SHEAR)
        for (int k = 1; k <= 12; k++) obs[n++] = (rod_fit_obs){0.3, 0.15 * k / 12, 0, 0};
    truth(s, obs, n);
    double sg = parts & LOWER ? -1.0 : 1.0;
    store_samples *w = NULL;
    assert_int_equal(store_samples_begin(st, id, NULL, &w, why, sizeof why), STORE_OK);
    double tt = 0.0;
    for (int k = 1; k <= 5; k++) frame(w, tt += 0.1, 0.04 * k, 0.0, 0.01, 0.7); /* low: no upper state */
    for (int k = 0; k < nc; k++) frame(w, tt += 0.1, obs[k].dl, obs[k].dw, sg * obs[k].dz, obs[k].a);
    event(st, id, tt += 0.05, "state shearing");
    for (int k = nc; k < n; k++) frame(w, tt += 0.1, obs[k].dl, obs[k].dw, sg * obs[k].dz, obs[k].a);
    frame(w, tt += 0.1, 0.3, 0.17, 0.9, 1.5);  /* past the cut-off (0.8 of the snap, 0.16) */
    frame(w, tt += 0.1, 0.3, 0.20, -0.2, 0.0); /* the snap itself */
    event(st, id, tt += 0.05, "state returning");
    frame(w, tt += 0.1, 0.3, 0.1, 0.9, 2.0); /* the return */
    assert_int_equal(store_samples_end(w, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_result(st, id, true, 0.20, STORE_REGIME_SYMMETRIC, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_DONE, NULL, store_wall_now(), why, sizeof why),
                     STORE_OK);
    return id;
}

static int64_t a1, a2, b1, a_lower, spec_a, spec_b, r5, r10, k5, k10, j10;

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/test_ctl_calibrate_joint.XXXXXX");
    if (!mkdtemp(dir)) return 1;
    snprintf(db, sizeof db, "%s/trials.db", dir);
    store *st;
    char why[256];
    if (store_open(db, &st, why, sizeof why) != STORE_OK) return 1;
    a1 = add_trial(st, &S5, WITH_SHEAR);
    b1 = add_trial(st, &S10, WITH_SHEAR);
    a2 = add_trial(st, &S5, 0);
    a_lower = add_trial(st, &S5, LOWER);
    r5 = add_trial(st, &S5R, WITH_SHEAR);
    r10 = add_trial(st, &S10R, WITH_SHEAR);
    k5 = add_trial(st, &S5K, WITH_SHEAR);
    k10 = add_trial(st, &S10K, WITH_SHEAR);
    j10 = add_trial(st, &S10J, WITH_SHEAR);
    store_trial t;
    if (store_trial_get(st, a1, &t, why, sizeof why) != STORE_OK) return 1;
    spec_a = t.specimen_id;
    if (store_trial_get(st, b1, &t, why, sizeof why) != STORE_OK) return 1;
    spec_b = t.specimen_id;
    store_close(st);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : 1;
}

static json_t *param(json_t *spec, const char *key)
{
    json_t *ps = json_object_get(spec, "parameters");
    for (size_t i = 0; i < json_array_size(ps); i++)
        if (!strcmp(json_string_value(json_object_get(json_array_get(ps, i), "key")), key)) return json_array_get(ps, i);
    fail_msg("no parameter %s", key);
    return NULL;
}

static double fitted(json_t *spec, const char *key)
{
    return json_real_value(json_object_get(param(spec, key), "fitted"));
}

#define TIGHT "--set mesh.nodes=31 --sigma-dz 1e-4 --sigma-a 1e-3"

static void shares_the_hinge_per_width_and_writes_a_scene_each(void **state)
{
    (void)state;
    char args[512];
    /* The IDs in a mixed order: grouped by the specimen each first names. */
    snprintf(args, sizeof args, "%lld %lld %lld --share-hinge " TIGHT " --json --no-snap --write-scene %s/joint.ini",
             (long long)a1, (long long)b1, (long long)a2, dir);
    json_t *j = run_json(args);
    assert_true(json_is_true(json_object_get(j, "share_hinge")));
    json_t *h = json_object_get(j, "hinge_per_width");
    assert_string_equal(json_string_value(json_object_get(h, "key")), "folds.hinge_stiffness_per_width");
    assert_true(fabs(json_real_value(json_object_get(h, "start")) - 0.7) < 1e-9);
    assert_true(fabs(json_real_value(json_object_get(h, "fitted")) - 1.0) < 1e-3);
    assert_true(json_real_value(json_object_get(h, "se")) > 0.0);
    json_t *sp = json_object_get(j, "specimens");
    assert_int_equal(json_array_size(sp), 2);
    json_t *sa = json_array_get(sp, 0), *sb = json_array_get(sp, 1);
    assert_string_equal(json_string_value(json_object_get(sa, "specimen")), "S-5");
    assert_string_equal(json_string_value(json_object_get(sb, "specimen")), "S-10");
    assert_int_equal(json_array_size(json_object_get(sa, "trials")), 2);
    assert_int_equal(json_integer_value(json_object_get(sa, "samples")), 24);
    assert_int_equal(json_integer_value(json_object_get(sb, "samples")), 18);
    assert_true(fabs(json_real_value(json_object_get(sb, "width")) - 0.01) < 1e-15);
    assert_true(fabs(fitted(sa, "S-5:folds.angle_left_deg") + 86.0) < 1e-3);
    assert_true(fabs(fitted(sa, "S-5:folds.angle_right_deg") + 89.5) < 1e-3);
    assert_true(fabs(fitted(sb, "S-10:folds.angle_left_deg") + 88.0) < 1e-3);
    assert_true(fabs(fitted(sb, "S-10:folds.angle_right_deg") + 92.5) < 1e-3);
    assert_true(fabs(fitted(sb, "S-10:folds.hinge_stiffness") / 1e-2 - 1.0) < 1e-3);
    assert_true(fabs(json_real_value(json_object_get(param(sb, "S-10:folds.angle_left_deg"), "scene")) + 90.0) < 1e-12);
    assert_int_equal(json_array_size(json_object_get(j, "keys")), 5);
    assert_string_equal(json_string_value(json_array_get(json_object_get(j, "keys"), 3)), "S-10:folds.angle_left_deg");
    assert_int_equal(json_array_size(json_object_get(j, "correlation")), 5);
    /* One scene per specimen, FILE-specimen<ID>.ini, each with its own width and k = (k / b) b. */
    const spec_def *defs[2] = {&S5, &S10};
    int64_t ids[2] = {spec_a, spec_b};
    for (int s = 0; s < 2; s++) {
        char path[256];
        snprintf(path, sizeof path, "%s/joint-specimen%lld.ini", dir, (long long)ids[s]);
        assert_string_equal(json_string_value(json_object_get(json_array_get(sp, (size_t)s), "scene_written")), path);
        cfg_error err;
        rod_scene f;
        assert_int_equal(cfg_scene_load(path, NULL, 0, &f, &err), 0);
        assert_true(fabs(f.width - defs[s]->width) < 1e-15);
        assert_true(fabs(f.fold_hinge_stiffness / defs[s]->truth_k - 1.0) < 1e-3);
        assert_true(fabs(f.fold_angle_left_deg - defs[s]->truth_left) < 1e-3);
        assert_int_equal(f.nodes, 31);
    }
    json_decref(j);
}

static void prints_the_shared_hinge_and_each_snap(void **state)
{
    (void)state;
    char args[256];
    snprintf(args, sizeof args, "%lld %lld --share-hinge --set mesh.nodes=31", (long long)a1, (long long)b1);
    run_out r;
    run(&r, args);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "2 trials of 2 specimens, the hinge stiffness per unit width shared"));
    assert_non_null(strstr(r.out, "shared       folds.hinge_stiffness_per_width"));
    assert_non_null(strstr(r.out, "specimen     S-10: width 10 mm"));
    assert_non_null(strstr(r.out, "S-10:folds.angle_right_deg"));
    assert_non_null(strstr(r.out, "S-5:folds.hinge_stiffness"));
    /* a calibrated snap per specimen, beside its trial's measured and predicted snap */
    const char *c1 = strstr(r.out, "calibrated   snap Delta W");
    assert_non_null(c1);
    assert_non_null(strstr(c1 + 1, "calibrated   snap Delta W"));
    assert_non_null(strstr(r.out, "measured 0.20000 (symmetric): calibrated"));
    assert_non_null(strstr(r.out, "scene's prediction 0.21000"));
}

static void refusals_are_named(void **state)
{
    (void)state;
    char args[256];
    run_out r;
    snprintf(args, sizeof args, "%lld %lld " TIGHT, (long long)a1, (long long)b1);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "different specimens (S-5, S-10)"));
    assert_non_null(strstr(r.err, "--share-hinge"));
    snprintf(args, sizeof args, "%lld %lld --share-hinge " TIGHT " --set folds.hinge_stiffness=rigid", (long long)a1,
             (long long)b1);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "no hinge to share"));
    snprintf(args, sizeof args, "%lld %lld --share-hinge " TIGHT " --fit folds.angle_left_deg,folds.hinge_stiffness_left",
             (long long)a1, (long long)b1);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "not shared per unit width"));
    snprintf(args, sizeof args, "%lld 99 --share-hinge " TIGHT, (long long)a1);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "trial 99: no such trial"));
    snprintf(args, sizeof args, "%lld %lld --share-hinge " TIGHT, (long long)b1, (long long)a_lower);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "specimen S-5: trial"));
    assert_non_null(strstr(r.err, "lower state"));
}

/* Rigid creases in the trials' scenes and sim.fit_hinge in their rig file: the joint fit is set up
   as the in-trial fit is (trial_calibrate_setup), so the creases become hinges of the guess, the
   start of k / b is the guess over each width, and the truth comes back (before: "no hinge to
   share"). The priors (0.88 in ln(k / b), 10 deg) pull little at this noise. */
static void the_hinge_guess_makes_rigid_creases_hinges(void **state)
{
    (void)state;
    char args[256];
    snprintf(args, sizeof args, "%lld %lld --share-hinge " TIGHT " --json --no-snap", (long long)r5, (long long)r10);
    json_t *j = run_json(args);
    json_t *h = json_object_get(j, "hinge_per_width");
    double start = json_real_value(json_object_get(h, "start")), kb = json_real_value(json_object_get(h, "fitted"));
    double want_start = exp(0.5 * (log(FIT_HINGE / 0.005) + log(FIT_HINGE / 0.010)));
    printf("k / b started from %.6g N/rad (the guess over the widths: %.6g), fitted %.6g (truth 1)\n", start,
           want_start, kb);
    assert_true(fabs(start / want_start - 1.0) < 1e-9);
    assert_true(fabs(kb - 1.0) < 1e-2);
    json_t *sa = NULL, *sb = NULL, *sp = json_object_get(j, "specimens");
    for (size_t k = 0; k < json_array_size(sp); k++) {
        json_t *x = json_array_get(sp, k);
        if (!strcmp(json_string_value(json_object_get(x, "specimen")), "S-5r")) sa = x;
        if (!strcmp(json_string_value(json_object_get(x, "specimen")), "S-10r")) sb = x;
    }
    assert_non_null(sa);
    assert_non_null(sb);
    assert_true(fabs(fitted(sa, "S-5r:folds.angle_left_deg") + 86.0) < 1e-2);
    assert_true(fabs(fitted(sb, "S-10r:folds.angle_right_deg") + 92.5) < 1e-2);
    json_decref(j);
}

/* The trials' stored sim.fit_keys are the keys without --fit, as for one strip
   (trial_calibrate_setup): each specimen fits its left crease alone, the right one held at the
   prediction's -90 deg (the truth here), and both angles and k / b come back (before: both angles
   of each specimen, 5 keys). Specimens whose trials name other keys are refused with both named;
   --fit names the keys for all. */
static void the_trials_fit_keys_are_the_keys(void **state)
{
    (void)state;
    char args[256];
    run_out r;
    snprintf(args, sizeof args, "%lld %lld --share-hinge " TIGHT " --json --no-snap", (long long)k5, (long long)k10);
    json_t *j = run_json(args);
    json_t *keys = json_object_get(j, "keys");
    assert_int_equal(json_array_size(keys), 3);
    assert_string_equal(json_string_value(json_array_get(keys, 1)), "S-5k:folds.angle_left_deg");
    assert_string_equal(json_string_value(json_array_get(keys, 2)), "S-10k:folds.angle_left_deg");
    json_t *sp = json_object_get(j, "specimens");
    assert_true(fabs(fitted(json_array_get(sp, 0), "S-5k:folds.angle_left_deg") + 86.0) < 1e-3);
    assert_true(fabs(fitted(json_array_get(sp, 1), "S-10k:folds.angle_left_deg") + 88.0) < 1e-3);
    assert_true(fabs(json_real_value(json_object_get(json_object_get(j, "hinge_per_width"), "fitted")) - 1.0) < 1e-3);
    json_decref(j);

    snprintf(args, sizeof args, "%lld %lld --share-hinge " TIGHT " --no-snap", (long long)k5, (long long)j10);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "specimen S-10j's trials fit other keys (sim.fit_keys \"folds.angle_right_deg\") "
                                  "than specimen S-5k's (\"folds.angle_left_deg\")"));
    assert_non_null(strstr(r.err, "--fit"));
    snprintf(args, sizeof args, "%lld %lld --share-hinge " TIGHT " --no-snap --json --fit folds.angle_left_deg",
             (long long)k5, (long long)j10);
    j = run_json(args);
    assert_int_equal(json_array_size(json_object_get(j, "keys")), 3);
    json_decref(j);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(shares_the_hinge_per_width_and_writes_a_scene_each),
        cmocka_unit_test(prints_the_shared_hinge_and_each_snap),
        cmocka_unit_test(refusals_are_named),
        cmocka_unit_test(the_hinge_guess_makes_rigid_creases_hinges),
        cmocka_unit_test(the_trials_fit_keys_are_the_keys),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
