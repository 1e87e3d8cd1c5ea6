/* phase_map.c: the predicted phase diagram on a thread of its own (see phase_map.h). */
#include "phase_map.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thread_class.h"

#define PHASE_MAP_NODES 41
#define PHASE_MAP_DT 0.01

enum { MAP_IDLE, MAP_COMPUTING, MAP_READY, MAP_FAILED };

struct phase_map {
    rod_scene scene;
    pthread_mutex_t lock; /* guards everything below but cancel */
    int state;
    int thread_started;
    pthread_t thread;
    size_t done, total;
    phase_grid grid; /* written by the thread before state becomes MAP_READY, then read-only */
    char why[256];
    atomic_int cancel;
};

phase_map *phase_map_create(const rod_scene *scene)
{
    phase_map *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    m->scene = *scene;
    m->scene.nodes = PHASE_MAP_NODES;
    m->scene.dt = PHASE_MAP_DT;
    pthread_mutex_init(&m->lock, NULL);
    atomic_init(&m->cancel, 0);
    m->total = 5 * 6;
    return m;
}

static void on_point(void *u, size_t done, size_t total)
{
    phase_map *m = u;
    pthread_mutex_lock(&m->lock);
    m->done = done;
    m->total = total;
    pthread_mutex_unlock(&m->lock);
}

static void *map_main(void *arg)
{
    phase_map *m = arg;
    /* This thread only, in SCHED_IDLE (a trial's rails may be moving; thread_class.h). Refused: nice
     * 19, the map is merely slower. */
    thread_class_idle_enter(NULL, 0);
    phase_grid g;
    char why[256] = "";
    int rc = phase_grid_compute(&m->scene, 30, 150, 5, 0.08, 0.28, 6, &g, on_point, m, &m->cancel, why, sizeof why);
    pthread_mutex_lock(&m->lock);
    if (rc == 0) {
        m->grid = g;
        m->state = MAP_READY;
    } else {
        snprintf(m->why, sizeof m->why, "%s", why);
        m->state = MAP_FAILED;
    }
    pthread_mutex_unlock(&m->lock);
    return NULL;
}

int phase_map_start(phase_map *m, char *why, size_t why_len)
{
    pthread_mutex_lock(&m->lock);
    int rc = 0;
    if (m->state == MAP_IDLE) {
        m->state = MAP_COMPUTING;
        if (pthread_create(&m->thread, NULL, map_main, m) == 0) {
            m->thread_started = 1;
        } else {
            m->state = MAP_FAILED;
            snprintf(m->why, sizeof m->why, "cannot start the phase map's thread");
            snprintf(why, why_len, "%s", m->why);
            rc = -1;
        }
    }
    pthread_mutex_unlock(&m->lock);
    return rc;
}

const phase_grid *phase_map_grid(phase_map *m)
{
    pthread_mutex_lock(&m->lock);
    const phase_grid *g = m->state == MAP_READY ? &m->grid : NULL;
    pthread_mutex_unlock(&m->lock);
    return g;
}

void phase_map_state(phase_map *m, char *line, size_t line_len)
{
    pthread_mutex_lock(&m->lock);
    switch (m->state) {
    case MAP_IDLE: snprintf(line, line_len, "not started"); break;
    case MAP_COMPUTING: snprintf(line, line_len, "computing %zu/%zu", m->done, m->total); break;
    case MAP_READY:
        snprintf(line, line_len, "ready (%zu points, N = %d)", m->grid.n_phi * m->grid.n_gamma, m->scene.nodes);
        break;
    default: snprintf(line, line_len, "failed: %s", m->why); break;
    }
    pthread_mutex_unlock(&m->lock);
}

void phase_map_free(phase_map *m)
{
    if (!m) return;
    atomic_store(&m->cancel, 1);
    pthread_mutex_lock(&m->lock);
    int joined = m->thread_started;
    pthread_mutex_unlock(&m->lock);
    if (joined) pthread_join(m->thread, NULL);
    phase_grid_free(&m->grid);
    pthread_mutex_destroy(&m->lock);
    free(m);
}
