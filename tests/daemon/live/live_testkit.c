/* live_testkit.c: ribbond as a child process and libcurl exchanges (see live_testkit.h). */
#include "live_testkit.h"

#include <curl/curl.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

double kit_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void kit_sleep_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

void kit_fresh_dir(const char *name, char *dir, size_t n)
{
    snprintf(dir, n, "%s/../test-output/%s", RIBBON_BIN_DIR, name);
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s'", dir, dir);
    if (system(cmd) != 0) fprintf(stderr, "cannot make %s\n", dir);
}

int kit_ribbond_start(ribbond_child *c, const char *dir, unsigned port, const char *const *sets)
{
    return kit_ribbond_start_config(c, dir, "mock.ini", port, sets);
}

int kit_ribbond_start_config(ribbond_child *c, const char *dir, const char *config, unsigned port,
                             const char *const *sets)
{
    memset(c, 0, sizeof *c);
    snprintf(c->dir, sizeof c->dir, "%s", dir);
    snprintf(c->log, sizeof c->log, "%s/ribbond.log", dir);
    char portset[64];
    snprintf(portset, sizeof portset, "api.port=%u", port);
    const char *argv[40];
    int k = 0;
    static char bin[300], cfg[300];
    snprintf(bin, sizeof bin, "%s/ribbond", RIBBON_BIN_DIR);
    snprintf(cfg, sizeof cfg, "%s/config/%s", RIBBON_SOURCE_DIR, config);
    argv[k++] = bin;
    argv[k++] = "--config";
    argv[k++] = cfg;
    argv[k++] = "--set";
    argv[k++] = portset;
    for (int i = 0; sets && sets[i] && k < 36; i++) {
        argv[k++] = "--set";
        argv[k++] = sets[i];
    }
    argv[k] = NULL;
    pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        if (chdir(dir) != 0) _exit(126);
        int fd = open(c->log, O_WRONLY | O_CREAT | O_APPEND, 0644);
        if (fd >= 0) {
            dup2(fd, 2);
            dup2(fd, 1);
        }
        execv(bin, (char *const *)argv);
        _exit(127);
    }
    c->pid = pid;
    double t0 = kit_now();
    while (kit_now() - t0 < 60) {
        FILE *f = fopen(c->log, "r");
        char line[1024];
        while (f && fgets(line, sizeof line, f)) {
            const char *p = strstr(line, "listening on http://127.0.0.1:");
            if (p) {
                c->port = (unsigned)atoi(p + strlen("listening on http://127.0.0.1:"));
                snprintf(c->url, sizeof c->url, "http://127.0.0.1:%u", c->port);
                fclose(f);
                return 0;
            }
        }
        if (f) fclose(f);
        int st;
        if (waitpid(pid, &st, WNOHANG) == pid) break;
        kit_sleep_ms(50);
    }
    char cmd[400];
    snprintf(cmd, sizeof cmd, "cat '%s' >&2", c->log);
    if (system(cmd) != 0) fprintf(stderr, "(no log)\n");
    kill(pid, SIGKILL);
    waitpid(pid, NULL, 0);
    c->pid = 0;
    return -1;
}

int kit_ribbond_stop(ribbond_child *c)
{
    if (c->pid <= 0) return -1;
    kill(c->pid, SIGTERM);
    int st = 0;
    double t0 = kit_now();
    while (waitpid(c->pid, &st, WNOHANG) == 0) {
        if (kit_now() - t0 > 60) {
            kill(c->pid, SIGKILL);
            waitpid(c->pid, &st, 0);
            break;
        }
        kit_sleep_ms(20);
    }
    c->pid = 0;
    return st;
}

size_t kit_curl_collect(char *d, size_t sz, size_t nm, void *u)
{
    kit_body *g = u;
    size_t k = sz * nm;
    char *q = realloc(g->p, g->n + k + 1);
    if (!q) return 0;
    memcpy(q + g->n, d, k);
    g->p = q;
    g->n += k;
    g->p[g->n] = '\0';
    return k;
}

int kit_http(const char *method, const char *url, const char *token, const char *json_body, char **body,
             double timeout_s)
{
    CURL *h = curl_easy_init();
    if (!h) return -1;
    kit_body g = {calloc(1, 1), 0};
    struct curl_slist *hd = NULL;
    char auth[400];
    if (token) {
        snprintf(auth, sizeof auth, "Authorization: Bearer %s", token);
        hd = curl_slist_append(hd, auth);
    }
    if (json_body) hd = curl_slist_append(hd, "Content-Type: application/json");
    curl_easy_setopt(h, CURLOPT_URL, url);
    curl_easy_setopt(h, CURLOPT_CUSTOMREQUEST, method);
    if (json_body) curl_easy_setopt(h, CURLOPT_POSTFIELDS, json_body);
    curl_easy_setopt(h, CURLOPT_HTTPHEADER, hd);
    curl_easy_setopt(h, CURLOPT_WRITEFUNCTION, kit_curl_collect);
    curl_easy_setopt(h, CURLOPT_WRITEDATA, &g);
    curl_easy_setopt(h, CURLOPT_TIMEOUT_MS, (long)(timeout_s * 1000));
    curl_easy_setopt(h, CURLOPT_NOSIGNAL, 1L);
    long status = -1;
    CURLcode rc = curl_easy_perform(h);
    /* A stream never ends: after the timeout its status is still known (0 when nothing came). */
    if (rc == CURLE_OK || rc == CURLE_OPERATION_TIMEDOUT) curl_easy_getinfo(h, CURLINFO_RESPONSE_CODE, &status);
    if (status == 0) status = -1;
    curl_slist_free_all(hd);
    curl_easy_cleanup(h);
    if (body) *body = g.p;
    else free(g.p);
    return (int)status;
}
