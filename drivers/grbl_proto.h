/* grbl_proto.h: the GRBL 1.1 wire format: classifying reply lines, parsing `?` status reports,
 * and the text of GRBL's error and alarm codes.
 *
 * Pure functions over bytes, no I/O, so the driver, the simulator, the unit tests and the fuzz
 * target share one parser. A status report looks like
 *   <Idle|MPos:10.000,0.000,0.000|FS:0,0|WCO:0.000,0.000,0.000>
 * The state comes first (Idle, Run, Hold:0|1, Jog, Alarm, Door:0-3, Check, Home, Sleep); fields
 * follow in any order; unknown fields are skipped; a report with neither MPos nor WPos is
 * refused. A WPos-only report is flagged (work_pos) so the caller can add a WCO remembered from
 * an earlier report, or refuse it: GRBL sends WCO only now and then. Every refusal names the byte offset and what was expected there. */
#ifndef RIBBON_DRIVERS_GRBL_PROTO_H
#define RIBBON_DRIVERS_GRBL_PROTO_H

#include <stdbool.h>
#include <stddef.h>

#define GRBL_MAX_AXES 3

typedef enum grbl_state {
    GRBL_IDLE = 0,
    GRBL_RUN,
    GRBL_HOLD,
    GRBL_JOG,
    GRBL_ALARM,
    GRBL_DOOR,
    GRBL_CHECK,
    GRBL_HOME,
    GRBL_SLEEP,
    GRBL_STATE_COUNT
} grbl_state;

typedef struct grbl_report {
    grbl_state state;
    int substate;                 /* Hold:0/1, Door:0..3; -1 if none */
    double pos[GRBL_MAX_AXES];    /* mm, machine position: MPos, or WPos + WCO of this report */
    int n_axes;                   /* axes present in the report */
    bool have_pos;
    bool work_pos;                /* the report had WPos only: pos is WPos (+ wco if have_wco) */
    bool have_wco;                /* the report carried WCO (GRBL sends it every 10-30 reports) */
    double wco[GRBL_MAX_AXES];    /* mm, work coordinate offset when have_wco */
    double feed_mm_min;           /* mm/min, current feed (FS or F field), 0 if absent */
    int buffer_blocks;            /* Bf: planner blocks available, -1 if absent */
} grbl_report;

typedef enum grbl_line_kind {
    GRBL_LINE_EMPTY = 0,
    GRBL_LINE_OK,        /* "ok" */
    GRBL_LINE_ERROR,     /* "error:N" */
    GRBL_LINE_ALARM,     /* "ALARM:N" */
    GRBL_LINE_STATUS,    /* "<...>" */
    GRBL_LINE_WELCOME,   /* "Grbl 1.1h ['$' for help]" after reset */
    GRBL_LINE_MESSAGE,   /* "[...]" feedback messages */
    GRBL_LINE_OTHER      /* settings dumps and anything else */
} grbl_line_kind;

/* Classify one line (without its line ending); *code gets N of error:N / ALARM:N, else 0. */
grbl_line_kind grbl_line_classify(const char *line, size_t len, int *code);
/* Parse a status report line; returns false with a reason naming the byte offset. */
bool grbl_status_parse(const char *line, size_t len, grbl_report *out, char *why, size_t why_len);
const char *grbl_state_name(grbl_state s);
const char *grbl_error_text(int code);
const char *grbl_alarm_text(int code);

#endif
