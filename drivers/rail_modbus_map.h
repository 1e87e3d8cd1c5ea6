/* rail_modbus_map.h: a Modbus drive's register map (where the drive keeps each value, how wide,
 * in which word order, the control values and status bits), the presets by name, the map's
 * cross-field checks and the 32-bit word order helpers (rail_modbus_map.c, where the presets'
 * sources are cited). The driver (rail_modbus.h), the simulator and the fuzz target use it. */
#ifndef RIBBON_DRIVERS_RAIL_MODBUS_MAP_H
#define RIBBON_DRIVERS_RAIL_MODBUS_MAP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "rail.h"

typedef enum rail_mb_word_order {
    RAIL_MB_HIGH_FIRST = 0,  /* 32-bit value: high word at the lower address (most drives) */
    RAIL_MB_LOW_FIRST = 1
} rail_mb_word_order;

/* Which Modbus table a value lives in. The driver writes holding registers only and reads
 * holding or input registers; coils and discrete inputs (one bit each) serve the probe's
 * information rows (rail_modbus_probe.h) and may not carry a role the driver uses. */
typedef enum rail_mb_kind {
    RAIL_MB_HOLDING = 0,  /* function 3 read, 16 write */
    RAIL_MB_INPUT = 1,    /* function 4 read, read-only */
    RAIL_MB_COIL = 2,     /* function 1 read (probe only) */
    RAIL_MB_DISCRETE = 3  /* function 2 read (probe only) */
} rail_mb_kind;

/* Whether a value is signed: ROLE keeps the role's own reading (positions, velocity, load signed;
 * status, alarm, identity unsigned; every 32-bit value signed), the others force it. */
typedef enum rail_mb_sign {
    RAIL_MB_SIGN_ROLE = 0,
    RAIL_MB_SIGNED = 1,
    RAIL_MB_UNSIGNED = 2
} rail_mb_sign;

/* One value: addr < 0 means the drive has no such register. */
typedef struct rail_mb_reg {
    int addr;           /* register address (0-based, as on the wire) */
    int words;          /* 1 (16-bit) or 2 (32-bit) */
    rail_mb_kind kind;  /* holding unless a map file says otherwise */
    rail_mb_sign sign;
    char meaning[96];   /* the drive manual's words for it (map files; "" = none given) */
} rail_mb_reg;

/* A register read only by the probe, to check the map against the manual (a map file's
 * [info.NAME] sections: firmware version, temperatures, a parameter the lab set by hand). */
#define RAIL_MB_INFO_MAX 16
typedef struct rail_mb_info {
    char name[32];
    rail_mb_reg reg;
    double scale;       /* unit per register count (0 = 1) */
    char unit[16];      /* "" = a bare number */
} rail_mb_info;

typedef struct rail_modbus_map {
    char name[32];
    bool verified;                 /* tried on the real drive */
    char source[200];              /* where the map comes from (document, section) */
    rail_mb_word_order word_order;
    double counts_per_mm;          /* position counts per mm (0: must be set in config) */
    double speed_per_mm_s;         /* drive speed units per mm/s (0: = counts_per_mm) */
    double accel_per_mm_s2;        /* drive acceleration units per mm/s^2 (0: = counts_per_mm) */
    rail_mb_reg target_pos, speed, accel, decel, op_type, trigger, control;
    rail_mb_reg actual_pos, actual_vel, status, alarm, watchdog, ident;
    rail_mb_reg load;              /* optional (addr -1 = none): a signed load reading, torque or
                                      following error, read with every status (rail_status.load) */
    double load_scale;             /* rail_status.load per register count (e.g. 0.1 for a torque
                                      register in 0.1 % units); finite and non-zero */
    long op_type_abs;              /* value of op_type meaning "absolute positioning" */
    long trigger_value;            /* written to trigger to start the move */
    long ctl_stop, ctl_estop, ctl_home, ctl_reset; /* control values; 0 = not supported */
    unsigned long st_ready, st_moving, st_in_pos, st_alarm, st_homing, st_home_end; /* bit masks */
    long ident_value;              /* expected identity register value, -1 = any */
    double watchdog_units_per_s;   /* watchdog register units per second (ms: 1000) */
    rail_mb_info info[RAIL_MB_INFO_MAX]; /* probe-only registers (map files) */
    int n_info;
    char file[160];                /* the map file it was read from ("" = a built-in preset) */
} rail_modbus_map;

/* The map's roles by index 0..RAIL_MB_ROLES-1, for map files, messages and the probe: the name
 * (as in reg_NAME and [reg.NAME]; NULL past the end) and the register in m. */
#define RAIL_MB_ROLES 14
const char *rail_modbus_role_name(int i);
rail_mb_reg *rail_modbus_role(rail_modbus_map *m, int i);
const rail_mb_reg *rail_modbus_role_c(const rail_modbus_map *m, int i);
/* 1 when the driver writes the role (it must then be a holding register). */
int rail_modbus_role_written(int i);
const char *rail_mb_kind_name(rail_mb_kind k);

/* Fill a preset by name ("ribbon-sim", "oriental-az"); RAIL_E_INVALID for an unknown name. */
rail_err rail_modbus_preset(const char *name, rail_modbus_map *out);
/* The warning an unverified map carries ("" for a verified one): its name, its file (or
 * "built-in") and its source, for the probe and for ribbond's log when allow_unverified lets it
 * drive. Returns 1 when there is one. */
int rail_modbus_map_warning(const rail_modbus_map *m, char *out, size_t n);
/* Cross-field checks of a map; names the field. */
rail_err rail_modbus_map_check(const rail_modbus_map *m, char *why, size_t why_len);

/* Word order helpers (also used by the simulator and the fuzz target). */
void rail_mb_put32(uint16_t *w, int32_t v, rail_mb_word_order o);
int32_t rail_mb_get32(const uint16_t *w, rail_mb_word_order o);

#endif
