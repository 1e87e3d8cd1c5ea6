/* cfg_datetime.h: the one date-time grammar of values that come from outside (today the rig
 * file's specimen.folded_at): an ISO 8601 calendar date and time of day with an explicit zone,
 *
 *   date-time = YYYY "-" MM "-" DD ( "T" | " " ) hh ":" mm [ ":" ss [ "." digits ] ] zone
 *   zone      = "Z" | ( "+" | "-" ) hh ":" mm
 *
 * A zone is required: without one the text would mean the reading computer's local time, and a
 * crease's age (hours matter: a released crease relaxes logarithmically) would depend on where
 * the daemon runs. Fields are range-checked (month 1-12, the month's days with leap years,
 * hh 0-23, mm 0-59, ss 0-59: no leap second). Nothing here allocates, keeps state or reads
 * the clock. */
#ifndef RIBBON_CONFIG_CFG_DATETIME_H
#define RIBBON_CONFIG_CFG_DATETIME_H

#include <stddef.h>

typedef enum cfg_datetime_status {
    CFG_DATETIME_OK = 0,
    CFG_DATETIME_SYNTAX, /* not of the form above (why says where) */
    CFG_DATETIME_RANGE,  /* a field out of range: month 13, 30 February, 24:00 */
    CFG_DATETIME_NO_ZONE /* a date-time without "Z" or an offset */
} cfg_datetime_status;

/* Parse the whole of s (no surrounding spaces) into seconds since the Unix epoch, UTC. On failure
 * *epoch_s is untouched and why (may be NULL) says what is wrong. */
cfg_datetime_status cfg_datetime_parse(const char *s, double *epoch_s, char *why, size_t why_len);

#endif
