/* mock_daemon.h: ribbond in process for the tests that run whole mock trials through its API
 * operations (rig_daemon_ops), shared so that each such test keeps only what it checks:
 * config/mock.ini with its store and videos in a temporary directory, everything at N = 31 and the
 * simulators' dt 2e-3 for speed, plus the test's own overrides; a trial started with a JSON body and
 * followed until ribbond is idle again (the session finished: the fits and the specimen's refit
 * after it included); the trial's JSON as GET /trials/ID gives it. Built into each test that uses
 * it (SOURCES ../mock_daemon.c ../test_dir.c); failures end the test through cmocka. */
#ifndef RIBBON_TESTS_MOCK_DAEMON_H
#define RIBBON_TESTS_MOCK_DAEMON_H

#include <stdint.h>

#include <jansson.h>

#include "rig_daemon.h"

enum { MOCK_DAEMON_MAX_SETS = 16 };

typedef struct mock_daemon {
    char dir[64]; /* the temporary directory: trials.db, videos/ */
    rig_daemon d;
} mock_daemon;

/* Opens ribbond on config/mock.ini in a new directory /tmp/NAME-XXXXXX with the common overrides
 * (store.path, camera.video_dir, api.port=0, mesh.nodes=31, sim.nodes=31, sim.dt=2e-3,
 * twin.mesh.nodes=31, twin.solver.dt=2e-3), then the n_sets of sets (at most MOCK_DAEMON_MAX_SETS). */
void mock_daemon_open(mock_daemon *m, const char *name, const char *const *sets, int n_sets);
/* Starts a trial with the request body (JSON text; NULL: "{}") and waits until ribbond is idle
 * (at most 300 s). Returns its id. */
int64_t mock_daemon_trial(mock_daemon *m, const char *body);
/* The trial's JSON (the API's show), the caller's to free. */
json_t *mock_daemon_show(mock_daemon *m, int64_t id);
/* Closes ribbond and removes the directory (test_dir_done, kept with RIBBON_TEST_KEEP=1). */
void mock_daemon_close(mock_daemon *m, const char *what);

#endif
