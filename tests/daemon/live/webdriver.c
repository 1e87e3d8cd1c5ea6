/* webdriver.c: a minimal WebDriver client over libcurl and jansson (see webdriver.h). */
#include "webdriver.h"
#include "live_testkit.h"

#include <arpa/inet.h>
#include <curl/curl.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define CHROMIUM "/usr/bin/chromium"
#define CHROMEDRIVER "/usr/bin/chromedriver"

int wd_available(void)
{
    return access(CHROMIUM, X_OK) == 0 && access(CHROMEDRIVER, X_OK) == 0;
}

/* One WebDriver command; returns the reply's "value" (new reference) or NULL with why. */
static json_t *call(webdriver *wd, const char *method, const char *path, json_t *body, double timeout_s, char *why,
                    size_t why_len)
{
    char url[512];
    snprintf(url, sizeof url, "%s%s", wd->base, path);
    CURL *h = curl_easy_init();
    kit_body b = {NULL, 0};
    char *text = body ? json_dumps(body, JSON_COMPACT) : NULL;
    struct curl_slist *hd = curl_slist_append(NULL, "Content-Type: application/json");
    curl_easy_setopt(h, CURLOPT_URL, url);
    curl_easy_setopt(h, CURLOPT_CUSTOMREQUEST, method);
    if (text) curl_easy_setopt(h, CURLOPT_POSTFIELDS, text);
    curl_easy_setopt(h, CURLOPT_HTTPHEADER, hd);
    curl_easy_setopt(h, CURLOPT_WRITEFUNCTION, kit_curl_collect);
    curl_easy_setopt(h, CURLOPT_WRITEDATA, &b);
    curl_easy_setopt(h, CURLOPT_TIMEOUT_MS, (long)(timeout_s * 1000));
    curl_easy_setopt(h, CURLOPT_NOSIGNAL, 1L);
    CURLcode rc = curl_easy_perform(h);
    curl_slist_free_all(hd);
    curl_easy_cleanup(h);
    free(text);
    if (rc != CURLE_OK) {
        snprintf(why, why_len, "%s %s: %s", method, path, curl_easy_strerror(rc));
        free(b.p);
        return NULL;
    }
    json_error_t e;
    json_t *j = b.p ? json_loads(b.p, 0, &e) : NULL;
    if (!j) {
        snprintf(why, why_len, "%s %s: reply is not JSON: %.200s", method, path, b.p ? b.p : "");
        free(b.p);
        return NULL;
    }
    free(b.p);
    json_t *v = json_object_get(j, "value");
    json_t *err = json_is_object(v) ? json_object_get(v, "error") : NULL;
    if (err) {
        snprintf(why, why_len, "%s %s: %s: %.300s", method, path, json_string_value(err),
                 json_string_value(json_object_get(v, "message")));
        json_decref(j);
        return NULL;
    }
    json_incref(v);
    json_decref(j);
    return v ? v : json_null();
}

static unsigned free_port(void)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t l = sizeof a;
    unsigned p = 0;
    if (bind(fd, (struct sockaddr *)&a, sizeof a) == 0 && getsockname(fd, (struct sockaddr *)&a, &l) == 0)
        p = ntohs(a.sin_port);
    close(fd);
    return p;
}

int wd_open(webdriver *wd, const char *profile_dir, int w, int h, char *why, size_t why_len)
{
    memset(wd, 0, sizeof *wd);
    snprintf(wd->profile, sizeof wd->profile, "%s", profile_dir);
    unsigned port = free_port();
    snprintf(wd->base, sizeof wd->base, "http://127.0.0.1:%u", port);
    char portarg[32];
    snprintf(portarg, sizeof portarg, "--port=%u", port);
    pid_t pid = fork();
    if (pid < 0) {
        snprintf(why, why_len, "fork failed");
        return -1;
    }
    if (pid == 0) {
        int fd = open("/dev/null", O_WRONLY);
        if (fd >= 0) {
            dup2(fd, 1);
            dup2(fd, 2);
        }
        execl(CHROMEDRIVER, CHROMEDRIVER, portarg, "--allowed-ips=127.0.0.1", (char *)NULL);
        _exit(127);
    }
    wd->driver_pid = pid;
    json_t *ready = NULL;
    for (int k = 0; k < 200 && !ready; k++) {
        struct timespec ts = {0, 50 * 1000000L};
        nanosleep(&ts, NULL);
        ready = call(wd, "GET", "/status", NULL, 2, why, why_len);
    }
    if (!ready) {
        wd_close(wd);
        return -1;
    }
    json_decref(ready);
    char size[64], udd[400];
    snprintf(size, sizeof size, "--window-size=%d,%d", w, h);
    snprintf(udd, sizeof udd, "--user-data-dir=%s", profile_dir);
    json_t *args = json_pack("[s,s,s,s,s,s,s,s,s,s,s]", "--headless", "--disable-gpu", "--no-sandbox", "--disable-quic",
                             "--no-first-run", "--disable-background-networking", "--disable-component-update",
                             "--disable-sync", "--disable-dev-shm-usage", size, udd);
    json_t *caps = json_pack("{s:{s:{s:s, s:{s:s, s:o}, s:{s:s}}}}", "capabilities", "alwaysMatch", "browserName",
                             "chrome", "goog:chromeOptions", "binary", CHROMIUM, "args", args, "goog:loggingPrefs",
                             "browser", "ALL");
    json_t *v = call(wd, "POST", "/session", caps, 60, why, why_len);
    json_decref(caps);
    if (!v) {
        wd_close(wd);
        return -1;
    }
    const char *sid = json_string_value(json_object_get(v, "sessionId"));
    snprintf(wd->session, sizeof wd->session, "%s", sid ? sid : "");
    json_decref(v);
    if (!wd->session[0]) {
        snprintf(why, why_len, "chromedriver gave no session id");
        wd_close(wd);
        return -1;
    }
    return 0;
}

int wd_navigate(webdriver *wd, const char *url, char *why, size_t why_len)
{
    char path[200];
    snprintf(path, sizeof path, "/session/%s/url", wd->session);
    json_t *b = json_pack("{s:s}", "url", url);
    json_t *v = call(wd, "POST", path, b, 60, why, why_len);
    json_decref(b);
    if (!v) return -1;
    json_decref(v);
    return 0;
}

json_t *wd_exec(webdriver *wd, const char *script, char *why, size_t why_len)
{
    char path[200];
    snprintf(path, sizeof path, "/session/%s/execute/sync", wd->session);
    json_t *b = json_pack("{s:s, s:[]}", "script", script, "args");
    json_t *v = call(wd, "POST", path, b, 30, why, why_len);
    json_decref(b);
    return v;
}

static int b64(int c)
{
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
}

int wd_screenshot(webdriver *wd, const char *png_path, char *why, size_t why_len)
{
    char path[200];
    snprintf(path, sizeof path, "/session/%s/screenshot", wd->session);
    json_t *v = call(wd, "GET", path, NULL, 60, why, why_len);
    if (!v) return -1;
    const char *s = json_string_value(v);
    size_t len = s ? strlen(s) : 0;
    unsigned char *out = malloc(len * 3 / 4 + 4);
    size_t o = 0;
    unsigned acc = 0;
    int bits = 0;
    for (size_t i = 0; i < len; i++) {
        int d = b64((unsigned char)s[i]);
        if (d < 0) continue;
        acc = (acc << 6) | (unsigned)d;
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out[o++] = (unsigned char)(acc >> bits);
        }
    }
    json_decref(v);
    FILE *f = fopen(png_path, "wb");
    int rc = f && fwrite(out, 1, o, f) == o ? 0 : -1;
    if (f) fclose(f);
    free(out);
    if (rc) snprintf(why, why_len, "cannot write %s", png_path);
    return rc;
}

json_t *wd_console(webdriver *wd, char *why, size_t why_len)
{
    char path[200];
    snprintf(path, sizeof path, "/session/%s/se/log", wd->session);
    json_t *b = json_pack("{s:s}", "type", "browser");
    json_t *v = call(wd, "POST", path, b, 30, why, why_len);
    json_decref(b);
    return v;
}

void wd_close(webdriver *wd)
{
    if (wd->session[0]) {
        char path[200], why[256];
        snprintf(path, sizeof path, "/session/%s", wd->session);
        json_t *v = call(wd, "DELETE", path, NULL, 30, why, sizeof why);
        json_decref(v);
        wd->session[0] = '\0';
    }
    if (wd->driver_pid > 0) {
        kill(wd->driver_pid, SIGTERM);
        waitpid(wd->driver_pid, NULL, 0);
        wd->driver_pid = 0;
    }
}
