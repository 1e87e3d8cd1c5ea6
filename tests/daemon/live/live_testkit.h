/* live_testkit.h: what the live page's end-to-end tests share: ribbond in mock mode as a child
 * process in a fresh directory (stopped with SIGTERM), and one HTTP exchange with libcurl. */
#ifndef RIBBON_TESTS_LIVE_TESTKIT_H
#define RIBBON_TESTS_LIVE_TESTKIT_H

#include <stddef.h>
#include <sys/types.h>

typedef struct ribbond_child {
    pid_t pid;
    unsigned port;
    char url[64];
    char dir[256];
    char log[300];
} ribbond_child;

/* A fresh directory under the build folder for this test (dir gets its path). */
void kit_fresh_dir(const char *name, char *dir, size_t n);
/* Starts ribbond on config/mock.ini in dir, port (0 = any) and the extra --set overrides (NULL
 * terminated); waits for "listening on". Returns 0, or -1 (the log is printed). */
int kit_ribbond_start(ribbond_child *c, const char *dir, unsigned port, const char *const *sets);
/* The same on config/CONFIG (e.g. "replay.ini": replay mode on the store mock.ini filled). */
int kit_ribbond_start_config(ribbond_child *c, const char *dir, const char *config, unsigned port,
                             const char *const *sets);
/* SIGTERM and wait (at most 60 s, then SIGKILL). Returns the exit status. */
int kit_ribbond_stop(ribbond_child *c);

/* One request: status, body malloc'ed (NUL-terminated) in *body if body is not NULL. token may be
 * NULL. json_body (may be NULL) is sent with POST. Returns the HTTP status, or -1. */
/* A response body grown by kit_curl_collect (libcurl's write callback; p NUL-terminated, caller frees p). */
typedef struct kit_body {
    char *p;
    size_t n;
} kit_body;
size_t kit_curl_collect(char *d, size_t sz, size_t nm, void *body);

int kit_http(const char *method, const char *url, const char *token, const char *json_body, char **body,
             double timeout_s);

double kit_now(void);
void kit_sleep_ms(int ms);

#endif
