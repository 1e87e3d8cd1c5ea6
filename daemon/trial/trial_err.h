/* trial_err.h: the trial layer's status: what a caller (the API, ribbonctl) needs to tell a user
 * apart, with the reason in the caller's why buffer. */
#ifndef RIBBON_TRIAL_ERR_H
#define RIBBON_TRIAL_ERR_H

typedef enum trial_err {
    TRIAL_OK = 0,
    TRIAL_E_REFUSED,  /* the request cannot run as asked (HTTP 400): e.g. its prediction's run-time
                         estimate exceeds the bound */
    TRIAL_E_NOTFOUND, /* no such trial (HTTP 404) */
    TRIAL_E_FAILED    /* the store, a thread or a device failed (HTTP 500) */
} trial_err;

#endif
