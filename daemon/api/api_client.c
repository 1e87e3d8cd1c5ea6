/* api_client.c: one HTTP exchange with ribbond over libcurl (see api_client.h).
 *
 * Design choices. A fresh easy handle per request: ribbonctl makes one or two requests per run,
 * so connection reuse buys nothing and statelessness makes the call safe from any thread.
 * Proxies are switched off (an http_proxy in the user's environment must not route the lab's
 * local daemon through a proxy). Only http and https are allowed, redirects are not followed,
 * and a reply larger than API_CLIENT_MAX_REPLY is refused rather than buffered without bound.
 * Bodies above 1 KiB are sent with "Expect: 100-continue", so that a server refusing them (413,
 * 401) answers before the upload instead of resetting the connection in the middle of it.
 * Errors are worded for the person at the terminal: what was tried, what happened, what to do. */
#include "api_client.h"

#include <ctype.h>
#include <curl/curl.h>
#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define API_CLIENT_MAX_REPLY (64u * 1024 * 1024)

api_client_config api_client_config_default(void)
{
    api_client_config c = {.base_url = "http://127.0.0.1:8377", .token = NULL, .timeout_s = 30.0};
    return c;
}

int api_client_global_init(char *why, size_t why_len)
{
    CURLcode rc = curl_global_init(CURL_GLOBAL_DEFAULT);
    if (rc != CURLE_OK) {
        snprintf(why, why_len, "cannot initialise libcurl: %s", curl_easy_strerror(rc));
        return -1;
    }
    return 0;
}

void api_client_global_cleanup(void)
{
    curl_global_cleanup();
}

/* The reply body, accumulated by on_data. */
typedef struct reply_buf {
    unsigned char *data;
    size_t len, cap;
    bool overflow; /* more than API_CLIENT_MAX_REPLY, or out of memory */
} reply_buf;

static size_t on_data(char *ptr, size_t size, size_t nmemb, void *userdata)
{
    reply_buf *b = userdata;
    size_t add = size * nmemb;
    if (add > API_CLIENT_MAX_REPLY - b->len) {
        b->overflow = true;
        return 0; /* makes curl stop with CURLE_WRITE_ERROR */
    }
    if (b->len + add + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->len + add + 1)
            cap *= 2;
        unsigned char *p = realloc(b->data, cap);
        if (p == NULL) {
            b->overflow = true;
            return 0;
        }
        b->data = p;
        b->cap = cap;
    }
    memcpy(b->data + b->len, ptr, add);
    b->len += add;
    b->data[b->len] = '\0'; /* so a text reply can be quoted in a message */
    return add;
}

/* The lower-cased OS reason for a failed connect ("connection refused"), else curl's text. */
static void connect_reason(CURL *h, CURLcode rc, const char *errbuf, char *out, size_t n)
{
    long oserr = 0;
    if (curl_easy_getinfo(h, CURLINFO_OS_ERRNO, &oserr) == CURLE_OK && oserr != 0)
        snprintf(out, n, "%s", strerror((int)oserr));
    else
        snprintf(out, n, "%s", errbuf[0] ? errbuf : curl_easy_strerror(rc));
    if (out[0] != '\0')
        out[0] = (char)tolower((unsigned char)out[0]);
}

static bool valid_header_value(const char *s)
{
    for (; *s; s++)
        if ((unsigned char)*s < 0x20 || (unsigned char)*s == 0x7f)
            return false;
    return true;
}

/* Interpret a completed exchange. Takes ownership of b->data. */
static int take_reply(const char *url, long status, const char *ctype, reply_buf *b, json_t **json_out,
                      unsigned char **bytes_out, size_t *len_out, char *why, size_t why_len)
{
    bool is_json = ctype != NULL && strncasecmp(ctype, "application/json", 16) == 0;
    if (is_json) {
        json_error_t err;
        json_t *j = json_loadb((const char *)(b->data ? b->data : (unsigned char *)""), b->len, 0, &err);
        free(b->data);
        b->data = NULL;
        if (j == NULL) {
            snprintf(why, why_len, "reply from ribbond at %s (HTTP %ld) is not valid JSON: %s at line %d, column %d", url,
                     status, err.text, err.line, err.column);
            return -1;
        }
        if (status >= 400) {
            const char *msg = json_string_value(json_object_get(j, "error"));
            if (msg)
                snprintf(why, why_len, "%s", msg);
            else
                snprintf(why, why_len, "HTTP %ld", status);
        } else if (why_len > 0) {
            why[0] = '\0';
        }
        if (json_out)
            *json_out = j;
        else
            json_decref(j);
        return 0;
    }
    /* Not JSON. */
    if (bytes_out == NULL && json_out != NULL) {
        snprintf(why, why_len, "reply from ribbond at %s (HTTP %ld) is not JSON (content type %s)", url, status,
                 ctype ? ctype : "none");
        free(b->data);
        b->data = NULL;
        return -1;
    }
    if (status >= 400) {
        /* Not from ribbond's error path (a proxy, another program on the port): quote its start. */
        size_t k = 0;
        const char *t = b->data ? (const char *)b->data : "";
        while (t[k] && t[k] != '\n' && t[k] != '\r' && k < 120)
            k++;
        snprintf(why, why_len, "HTTP %ld%s%.*s", status, k ? ": " : "", (int)k, t);
    } else if (why_len > 0) {
        why[0] = '\0';
    }
    if (bytes_out) {
        *bytes_out = b->data;
        if (len_out)
            *len_out = b->len;
        b->data = NULL;
    } else {
        free(b->data);
        b->data = NULL;
    }
    return 0;
}

/* The arguments a request needs, checked before anything is allocated. 0, or -1 with why. */
static int request_check(const api_client_config *c, const char *method, const char *path, char *why,
                         size_t why_len)
{
    if (c == NULL || c->base_url == NULL || method == NULL || path == NULL || path[0] != '/') {
        snprintf(why, why_len, "api_client_request: need a config with base_url, a method and a path starting with '/'");
        return -1;
    }
    if (strncmp(c->base_url, "http://", 7) != 0 && strncmp(c->base_url, "https://", 8) != 0) {
        snprintf(why, why_len, "daemon URL '%.200s' must start with http:// or https://", c->base_url);
        return -1;
    }
    if (!(c->timeout_s > 0.0) || c->timeout_s > 86400.0) {
        snprintf(why, why_len, "client timeout %g s is out of range (0 .. 86400]", c->timeout_s);
        return -1;
    }
    bool has_token = c->token != NULL && c->token[0] != '\0';
    if (has_token && !valid_header_value(c->token)) {
        snprintf(why, why_len, "the API token contains control characters");
        return -1;
    }
    for (const char *m = method; *m || m == method; m++)
        if (!isupper((unsigned char)*m)) {
            snprintf(why, why_len, "HTTP method '%.20s' must be upper-case letters", method);
            return -1;
        }
    return 0;
}

/* The request's headers (and the Authorization line, in *auth, which the caller frees). NULL
 * with why when memory runs out. */
static struct curl_slist *request_headers(const api_client_config *c, bool has_body, size_t payload_len,
                                          char **auth, char *why, size_t why_len)
{
    struct curl_slist *headers = NULL;
    headers = curl_slist_append(headers, "Accept: application/json, image/png");
    if (has_body)
        headers = curl_slist_append(headers, "Content-Type: application/json");
    if (payload_len > 1024)
        headers = curl_slist_append(headers, "Expect: 100-continue");
    else
        headers = curl_slist_append(headers, "Expect:");
    if (c->token != NULL && c->token[0] != '\0') {
        size_t alen = strlen(c->token) + 32;
        *auth = malloc(alen);
        if (*auth == NULL) {
            snprintf(why, why_len, "out of memory");
            curl_slist_free_all(headers);
            return NULL;
        }
        snprintf(*auth, alen, "Authorization: Bearer %s", c->token);
        headers = curl_slist_append(headers, *auth);
    }
    if (headers == NULL)
        snprintf(why, why_len, "out of memory");
    return headers;
}

/* Timeouts, no proxy, no redirects, http(s) only, the reply into b, the method and the body. */
static void request_options(CURL *h, const api_client_config *c, const char *url, const char *method,
                            const char *payload, size_t payload_len, bool has_body,
                            struct curl_slist *headers, reply_buf *b, char *errbuf)
{
    long timeout_ms = (long)(c->timeout_s * 1000.0);
    if (timeout_ms < 1)
        timeout_ms = 1;
    long connect_ms = timeout_ms < 5000 ? timeout_ms : 5000;
    curl_easy_setopt(h, CURLOPT_URL, url);
    curl_easy_setopt(h, CURLOPT_PROTOCOLS_STR, "http,https");
    curl_easy_setopt(h, CURLOPT_PROXY, "");
    curl_easy_setopt(h, CURLOPT_NOSIGNAL, 1L);
    curl_easy_setopt(h, CURLOPT_FOLLOWLOCATION, 0L);
    curl_easy_setopt(h, CURLOPT_TIMEOUT_MS, timeout_ms);
    curl_easy_setopt(h, CURLOPT_CONNECTTIMEOUT_MS, connect_ms);
    curl_easy_setopt(h, CURLOPT_ERRORBUFFER, errbuf);
    curl_easy_setopt(h, CURLOPT_HTTPHEADER, headers);
    curl_easy_setopt(h, CURLOPT_WRITEFUNCTION, on_data);
    curl_easy_setopt(h, CURLOPT_WRITEDATA, b);
    curl_easy_setopt(h, CURLOPT_USERAGENT, "ribbonctl");
    if (strcmp(method, "GET") == 0 && !has_body) {
        curl_easy_setopt(h, CURLOPT_HTTPGET, 1L);
    } else {
        if (strcmp(method, "POST") != 0)
            curl_easy_setopt(h, CURLOPT_CUSTOMREQUEST, method);
        if (has_body || strcmp(method, "POST") == 0) {
            curl_easy_setopt(h, CURLOPT_POSTFIELDS, payload ? payload : "");
            curl_easy_setopt(h, CURLOPT_POSTFIELDSIZE_LARGE, (curl_off_t)payload_len);
        }
    }
}

/* Why curl_easy_perform failed, in the user's terms (is ribbond running, timed out, too big). */
static void transfer_reason(CURL *h, CURLcode rc, const api_client_config *c, int blen, const char *method,
                            const char *path, const char *url, const char *errbuf, const reply_buf *b,
                            char *why, size_t why_len)
{
    char reason[256];
    switch (rc) {
    case CURLE_COULDNT_CONNECT:
        connect_reason(h, rc, errbuf, reason, sizeof reason);
        snprintf(why, why_len, "cannot reach ribbond at %.*s: %s; is it running? (ribbond --config FILE)", blen,
                 c->base_url, reason);
        break;
    case CURLE_COULDNT_RESOLVE_HOST:
        snprintf(why, why_len, "cannot reach ribbond at %.*s: unknown host (%s)", blen, c->base_url,
                 errbuf[0] ? errbuf : curl_easy_strerror(rc));
        break;
    case CURLE_OPERATION_TIMEDOUT:
        snprintf(why, why_len, "ribbond at %.*s did not answer %s %s within %g s", blen, c->base_url, method, path,
                 c->timeout_s);
        break;
    case CURLE_WRITE_ERROR:
        if (b->overflow) {
            snprintf(why, why_len, "reply to %s %s is larger than %u bytes (or memory ran out)", method, path,
                     API_CLIENT_MAX_REPLY);
            break;
        }
        /* fall through */
    default:
        snprintf(why, why_len, "%s %s failed: %s", method, url, errbuf[0] ? errbuf : curl_easy_strerror(rc));
        break;
    }
}

int api_client_request(const api_client_config *c, const char *method, const char *path, const json_t *body,
                       int *http_status, json_t **json_out, unsigned char **bytes_out, size_t *len_out, char *why,
                       size_t why_len)
{
    if (json_out)
        *json_out = NULL;
    if (bytes_out)
        *bytes_out = NULL;
    if (len_out)
        *len_out = 0;
    if (http_status)
        *http_status = 0;
    if (request_check(c, method, path, why, why_len) != 0)
        return -1;

    /* URL: base without trailing slashes, then path. */
    size_t blen = strlen(c->base_url);
    while (blen > 0 && c->base_url[blen - 1] == '/')
        blen--;
    size_t ulen = blen + strlen(path) + 1;
    char *url = malloc(ulen);
    char *payload = NULL;
    char *auth = NULL;
    struct curl_slist *headers = NULL;
    CURL *h = NULL;
    reply_buf b = {0};
    int result = -1;
    if (url == NULL) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    snprintf(url, ulen, "%.*s%s", (int)blen, c->base_url, path);

    size_t payload_len = 0;
    if (body != NULL) {
        payload = json_dumps(body, JSON_COMPACT | JSON_ENCODE_ANY);
        if (payload == NULL) {
            snprintf(why, why_len, "cannot encode the request body as JSON");
            goto done;
        }
        payload_len = strlen(payload);
    }

    h = curl_easy_init();
    if (h == NULL) {
        snprintf(why, why_len, "cannot create a libcurl handle (was api_client_global_init called?)");
        goto done;
    }
    headers = request_headers(c, body != NULL, payload_len, &auth, why, why_len);
    if (headers == NULL)
        goto done;

    char errbuf[CURL_ERROR_SIZE] = "";
    request_options(h, c, url, method, payload, payload_len, body != NULL, headers, &b, errbuf);
    CURLcode rc = curl_easy_perform(h);
    if (rc != CURLE_OK) {
        transfer_reason(h, rc, c, (int)blen, method, path, url, errbuf, &b, why, why_len);
        goto done;
    }

    long status = 0;
    char *ctype = NULL;
    curl_easy_getinfo(h, CURLINFO_RESPONSE_CODE, &status);
    curl_easy_getinfo(h, CURLINFO_CONTENT_TYPE, &ctype);
    if (http_status)
        *http_status = (int)status;
    result = take_reply(url, status, ctype, &b, json_out, bytes_out, len_out, why, why_len);

done:
    if (h)
        curl_easy_cleanup(h);
    curl_slist_free_all(headers);
    free(auth);
    free(payload); /* json_dumps: "free with free()" (jansson's default allocator) */
    free(b.data);
    free(url);
    return result;
}
