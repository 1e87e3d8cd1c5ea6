/* webdriver.h: just enough of the W3C WebDriver protocol to drive Debian's chromium through
 * chromedriver from a C test: start chromedriver on a loopback port, open a headless session,
 * navigate, run a script, save a screenshot, read the browser's console log, quit. */
#ifndef RIBBON_TESTS_WEBDRIVER_H
#define RIBBON_TESTS_WEBDRIVER_H

#include <jansson.h>
#include <stddef.h>
#include <sys/types.h>

typedef struct webdriver {
    pid_t driver_pid;
    char base[64];       /* http://127.0.0.1:PORT */
    char session[128];
    char profile[300];   /* the fresh --user-data-dir */
} webdriver;

/* 1 when /usr/bin/chromium and /usr/bin/chromedriver exist. */
int wd_available(void);
/* Starts chromedriver and a headless chromium session (window w x h). Returns 0, or -1 with why. */
int wd_open(webdriver *wd, const char *profile_dir, int w, int h, char *why, size_t why_len);
int wd_navigate(webdriver *wd, const char *url, char *why, size_t why_len);
/* Runs script (a function body; "return ..." gives the value) and returns the value (new
 * reference), or NULL with why. */
json_t *wd_exec(webdriver *wd, const char *script, char *why, size_t why_len);
int wd_screenshot(webdriver *wd, const char *png_path, char *why, size_t why_len);
/* The browser console entries since the last call: a JSON array of {level, message}. */
json_t *wd_console(webdriver *wd, char *why, size_t why_len);
void wd_close(webdriver *wd);

#endif
