/* test_predict_terms_cli.c: "leave out what a scene does not need" (issue 31): `ribbon-sim
 * predict --fast --json` (daemon/ribbon_sim_commands/sim_cmd_predict.c, called in-process) lists
 * the energy terms it evaluated and the stages it ran; a scene never pays for a term it does not
 * have. Five scenes, each a short run of the paper's Gamma = 0.13 scene at N = 31 up to
 * Delta W = 0.05 (under a second each):
 *   no gravity (the paper's scenes)  -> gravity 0;          with gravity -> gravity > 0
 *   damping 0                         -> damping 0, stage off; damped   -> damping > 0, stage on
 *   no creases (angle 0)              -> fold 0 and hinge 0
 *   rigid creases (the default)       -> fold > 0, hinge 0
 *   compliant hinges                  -> hinge > 0 (its own term), fold 0
 * and every scene evaluates stretch, bend and twist and runs the route and the shear. stdout and
 * stderr are redirected to temporary files around each call. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim_cmd.h"

#define SCENE RIBBON_SOURCE_DIR "/config/scenes/paper-gamma013.ini"

typedef struct counts {
    json_int_t stretch, bend, twist, fold, hinge, gravity, damping;
    int route, shear, stage_damping;
} counts;

static void slurp(FILE *f, char *buf, size_t len)
{
    rewind(f);
    size_t n = fread(buf, 1, len - 1, f);
    buf[n] = '\0';
}

static json_int_t term(json_t *t, const char *name)
{
    json_t *v = json_object_get(t, name);
    if (!json_is_integer(v)) print_error("term_evaluations.%s missing\n", name);
    assert_true(json_is_integer(v));
    return json_integer_value(v);
}

/* Runs predict --fast --json on the base scene with the extra overrides (NULL-terminated). */
static counts run_predict(const char *const *extra)
{
    const char *base[] = {"mesh.nodes=31", "protocol.shear_max=0.05"};
    char *argv[40];
    int argc = 0;
    argv[argc++] = "predict";
    argv[argc++] = "--scene";
    argv[argc++] = SCENE;
    for (size_t i = 0; i < 2; i++) {
        argv[argc++] = "--set";
        argv[argc++] = (char *)base[i];
    }
    for (int i = 0; extra && extra[i]; i++) {
        argv[argc++] = "--set";
        argv[argc++] = (char *)extra[i];
    }
    argv[argc++] = "--fast";
    argv[argc++] = "--json";
    argv[argc] = NULL;
    FILE *fo = tmpfile(), *fe = tmpfile();
    assert_true(fo && fe);
    fflush(stdout);
    fflush(stderr);
    int so = dup(STDOUT_FILENO), se = dup(STDERR_FILENO);
    assert_true(so >= 0 && se >= 0);
    assert_true(dup2(fileno(fo), STDOUT_FILENO) >= 0 && dup2(fileno(fe), STDERR_FILENO) >= 0);
    int status = sim_cmd_predict(argc, argv);
    fflush(stdout);
    fflush(stderr);
    assert_true(dup2(so, STDOUT_FILENO) >= 0 && dup2(se, STDERR_FILENO) >= 0);
    close(so);
    close(se);
    static char out[16384], err[4096];
    slurp(fo, out, sizeof out);
    slurp(fe, err, sizeof err);
    fclose(fo);
    fclose(fe);
    if (status) print_error("predict exited %d: %s\n", status, err);
    assert_int_equal(status, 0);
    json_error_t je;
    json_t *j = json_loads(out, 0, &je);
    assert_non_null(j);
    json_t *t = json_object_get(j, "term_evaluations"), *st = json_object_get(j, "stages");
    assert_true(json_is_object(t) && json_is_object(st));
    counts c = {term(t, "stretch"), term(t, "bend"),  term(t, "twist"),   term(t, "fold"),
                term(t, "hinge"),   term(t, "gravity"), term(t, "damping"), 0, 0, 0};
    c.route = json_is_true(json_object_get(st, "route"));
    c.shear = json_is_true(json_object_get(st, "shear"));
    c.stage_damping = json_is_true(json_object_get(st, "damping"));
    print_message("stretch %lld bend %lld twist %lld fold %lld hinge %lld gravity %lld damping %lld; "
                  "stages route %d shear %d damping %d; regime %s\n",
                  (long long)c.stretch, (long long)c.bend, (long long)c.twist, (long long)c.fold,
                  (long long)c.hinge, (long long)c.gravity, (long long)c.damping, c.route, c.shear,
                  c.stage_damping, json_string_value(json_object_get(j, "regime")));
    json_decref(j);
    assert_true(c.stretch > 0 && c.bend > 0 && c.twist > 0);
    assert_true(c.route && c.shear);
    return c;
}

static void test_gravity_only_when_on(void **state)
{
    (void)state;
    counts off = run_predict(NULL);
    assert_true(off.gravity == 0);
    const char *on_set[] = {"ribbon.gravity=0,0,-0.1", NULL}; /* 9.81 is too heavy for this 1 m strip */
    counts on = run_predict(on_set);
    assert_true(on.gravity > 0);
}

static void test_damping_only_when_on(void **state)
{
    (void)state;
    const char *off_set[] = {"solver.damping=0", NULL};
    counts off = run_predict(off_set);
    assert_true(off.damping == 0 && !off.stage_damping);
    counts on = run_predict(NULL); /* the paper scene's damping 0.5 1/s */
    assert_true(on.damping > 0 && on.stage_damping);
}

static void test_creases_as_their_model_asks(void **state)
{
    (void)state;
    const char *none_set[] = {"folds.angle_deg=0", NULL};
    counts none = run_predict(none_set);
    assert_true(none.fold == 0 && none.hinge == 0);
    counts rigid = run_predict(NULL);
    assert_true(rigid.fold > 0 && rigid.hinge == 0);
    const char *hinge_set[] = {"folds.hinge_stiffness=5e-3", NULL};
    counts hinge = run_predict(hinge_set);
    assert_true(hinge.hinge > 0 && hinge.fold == 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gravity_only_when_on),
        cmocka_unit_test(test_damping_only_when_on),
        cmocka_unit_test(test_creases_as_their_model_asks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
