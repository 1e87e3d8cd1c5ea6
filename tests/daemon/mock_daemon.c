/* mock_daemon.c: ribbond in process on config/mock.ini for the whole-trial tests (see
 * mock_daemon.h). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mock_daemon.h"
#include "test_dir.h"

void mock_daemon_open(mock_daemon *m, const char *name, const char *const *sets, int n_sets)
{
    snprintf(m->dir, sizeof m->dir, "/tmp/%s-XXXXXX", name);
    assert_non_null(mkdtemp(m->dir));
    assert_true(n_sets >= 0 && n_sets <= MOCK_DAEMON_MAX_SETS);
    static char set_store[128], set_video[128];
    snprintf(set_store, sizeof set_store, "store.path=%s/trials.db", m->dir);
    snprintf(set_video, sizeof set_video, "camera.video_dir=%s/videos", m->dir);
    const char *ov[8 + MOCK_DAEMON_MAX_SETS] = {set_store,      set_video,     "api.port=0",         "mesh.nodes=31",
                                                "sim.nodes=31", "sim.dt=2e-3", "twin.mesh.nodes=31", "twin.solver.dt=2e-3"};
    for (int k = 0; k < n_sets; k++) ov[8 + k] = sets[k];
    char why[512] = "";
    if (rig_daemon_open(&m->d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, 8 + n_sets, NULL, why, sizeof why))
        fail_msg("open: %s", why);
}

int64_t mock_daemon_trial(mock_daemon *m, const char *body_text)
{
    api_ops ops = rig_daemon_ops();
    json_t *body = json_loads(body_text ? body_text : "{}", 0, NULL), *out = NULL;
    assert_non_null(body);
    int http = 201;
    char why[512] = "";
    if (ops.start(&m->d, body, &out, &http, why, sizeof why)) fail_msg("start: %d %s", http, why);
    int64_t id = json_integer_value(json_object_get(out, "id"));
    json_decref(body);
    json_decref(out);
    for (int k = 0;; k++) {
        json_t *st = NULL;
        assert_int_equal(ops.status(&m->d, &st, why, sizeof why), 0);
        int idle = !strcmp(json_string_value(json_object_get(st, "state")), "idle");
        json_decref(st);
        if (idle) break;
        if (k > 6000) fail_msg("trial %lld did not end in 300 s", (long long)id);
        usleep(50000);
    }
    return id;
}

json_t *mock_daemon_show(mock_daemon *m, int64_t id)
{
    api_ops ops = rig_daemon_ops();
    json_t *out = NULL;
    int http = 200;
    char why[256];
    if (ops.show(&m->d, id, &out, &http, why, sizeof why)) fail_msg("show %lld: %s", (long long)id, why);
    return out;
}

void mock_daemon_close(mock_daemon *m, const char *what)
{
    rig_daemon_close(&m->d, "test done");
    test_dir_done(m->dir, 1, what);
}
