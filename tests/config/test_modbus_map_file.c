/* test_modbus_map_file.c: Modbus register map files (config/modbus_map_file.c). The shipped maps
 * (config/maps/) equal the built-in presets field by field, so a rig that names the file behaves
 * as one that names the preset; every register's address, table, width, sign and meaning, the
 * probe-only [info.NAME] registers; a rail section's `map = maps/NAME.ini` found relative to the
 * rig file with reg_ and counts_per_mm keys applied on top; and each kind of bad file refused
 * naming the file, the line and the "section.key". */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cmocka.h>

#include "modbus_map_file.h"
#include "rail_config.h"
#include "rig_config.h"

static void assert_same_map(const rail_modbus_map *a, const rail_modbus_map *b)
{
    assert_string_equal(a->name, b->name);
    assert_int_equal(a->verified, b->verified);
    assert_string_equal(a->source, b->source);
    assert_int_equal(a->word_order, b->word_order);
    assert_true(a->counts_per_mm == b->counts_per_mm);
    assert_true(a->speed_per_mm_s == b->speed_per_mm_s);
    assert_true(a->accel_per_mm_s2 == b->accel_per_mm_s2);
    assert_true(a->load_scale == b->load_scale);
    assert_true(a->watchdog_units_per_s == b->watchdog_units_per_s);
    for (int i = 0; i < RAIL_MB_ROLES; i++) {
        const rail_mb_reg *x = rail_modbus_role_c(a, i), *y = rail_modbus_role_c(b, i);
        if (x->addr != y->addr || x->words != y->words || x->kind != y->kind || x->sign != y->sign) {
            print_error("register %s: %d/%d/%d/%d against %d/%d/%d/%d\n", rail_modbus_role_name(i), x->addr,
                        x->words, x->kind, x->sign, y->addr, y->words, y->kind, y->sign);
            fail();
        }
    }
    assert_int_equal(a->op_type_abs, b->op_type_abs);
    assert_int_equal(a->trigger_value, b->trigger_value);
    assert_int_equal(a->ctl_stop, b->ctl_stop);
    assert_int_equal(a->ctl_estop, b->ctl_estop);
    assert_int_equal(a->ctl_home, b->ctl_home);
    assert_int_equal(a->ctl_reset, b->ctl_reset);
    assert_int_equal(a->st_ready, b->st_ready);
    assert_int_equal(a->st_moving, b->st_moving);
    assert_int_equal(a->st_in_pos, b->st_in_pos);
    assert_int_equal(a->st_alarm, b->st_alarm);
    assert_int_equal(a->st_homing, b->st_homing);
    assert_int_equal(a->st_home_end, b->st_home_end);
    assert_int_equal(a->ident_value, b->ident_value);
}

static void test_shipped_maps_equal_presets(void **s)
{
    (void)s;
    const char *names[] = {"ribbon-sim", "oriental-az"};
    for (int i = 0; i < 2; i++) {
        char path[512];
        snprintf(path, sizeof path, "%s/config/maps/%s.ini", RIBBON_SOURCE_DIR, names[i]);
        rail_modbus_map file, preset;
        cfg_error err;
        cfg_status st = modbus_map_file_load(path, &file, &err);
        if (st != CFG_OK) {
            char msg[700];
            print_error("%s\n", cfg_error_format(&err, msg, sizeof msg));
        }
        assert_int_equal(st, CFG_OK);
        assert_int_equal(rail_modbus_preset(names[i], &preset), RAIL_OK);
        assert_same_map(&file, &preset);
        assert_string_equal(file.file, path);
        assert_string_equal(file.status.meaning[0] ? "set" : "", "set"); /* every role says what it is */
    }
}

static void test_types_and_info(void **s)
{
    (void)s;
    const char *text = "[map]\nname = other\nverified = no\nword_order = low_first\ncounts_per_mm = 200\n"
                       "ctl_stop = 0x20\nst_moving = 0x2000\n"
                       "[reg.target_pos]\naddress = 0x10\nwidth = 32\n"
                       "[reg.actual_pos]\naddress = 0x100\ntype = input\nwidth = 32\nsigned = no\n"
                       "meaning = feedback position\n"
                       "[reg.status]\naddress = 7\ntype = input\n"
                       "[info.temp]\naddress = 30\ntype = input\nsigned = yes\nscale = 0.1\nunit = degC\n"
                       "meaning = driver temperature\n"
                       "[info.enabled]\naddress = 2\ntype = coil\n"
                       "[info.limit]\naddress = 4\ntype = discrete\n";
    rail_modbus_map m;
    cfg_error err;
    assert_int_equal(modbus_map_file_parse("x.ini", text, strlen(text), &m, &err), CFG_OK);
    assert_string_equal(m.name, "other");
    assert_false(m.verified);
    assert_int_equal(m.word_order, RAIL_MB_LOW_FIRST);
    assert_int_equal(m.target_pos.addr, 16);
    assert_int_equal(m.target_pos.words, 2);
    assert_int_equal(m.target_pos.kind, RAIL_MB_HOLDING);
    assert_int_equal(m.actual_pos.addr, 256);
    assert_int_equal(m.actual_pos.kind, RAIL_MB_INPUT);
    assert_int_equal(m.actual_pos.sign, RAIL_MB_UNSIGNED);
    assert_string_equal(m.actual_pos.meaning, "feedback position");
    assert_int_equal(m.status.kind, RAIL_MB_INPUT);
    assert_int_equal(m.status.sign, RAIL_MB_SIGN_ROLE);
    assert_int_equal(m.speed.addr, -1); /* no section: absent from the drive */
    assert_int_equal(m.ident_value, -1);
    assert_int_equal(m.n_info, 3);
    assert_string_equal(m.info[0].name, "temp");
    assert_int_equal(m.info[0].reg.sign, RAIL_MB_SIGNED);
    assert_true(m.info[0].scale == 0.1);
    assert_string_equal(m.info[0].unit, "degC");
    assert_int_equal(m.info[1].reg.kind, RAIL_MB_COIL);
    assert_int_equal(m.info[2].reg.kind, RAIL_MB_DISCRETE);
}

/* A bad file names file, line and section.key. */
static void expect_bad(const char *text, cfg_status status, int line, const char *key, const char *needle)
{
    rail_modbus_map m;
    cfg_error err;
    cfg_status st = modbus_map_file_parse("maps/bad.ini", text, strlen(text), &m, &err);
    char msg[700];
    cfg_error_format(&err, msg, sizeof msg);
    if (st != status || err.line != line || strcmp(err.key, key) || !strstr(msg, needle)) {
        print_error("status %d line %d key '%s' message '%s'; wanted %d %d '%s' '%s'\n", st, err.line, err.key, msg,
                    status, line, key, needle);
        fail();
    }
    assert_string_equal(err.file, "maps/bad.ini");
}

#define HEAD "[map]\nname = m\nverified = yes\n"

static void test_bad_files(void **s)
{
    (void)s;
    expect_bad(HEAD "[reg.status]\naddress = 3\ntype = word\n", CFG_ERR_VALUE, 6, "reg.status.type",
               "'word' is not holding, input, coil or discrete");
    expect_bad(HEAD "[reg.status]\naddress = 3\ntype = coil\n", CFG_ERR_VALUE, 6, "reg.status.type",
               "one bit");
    expect_bad(HEAD "[reg.status]\naddress = 3\nwidth = 24\n", CFG_ERR_VALUE, 6, "reg.status.width",
               "not 16 or 32");
    expect_bad(HEAD "[reg.stauts]\naddress = 3\n", CFG_ERR_UNKNOWN, 4, "reg.stauts", "no register role 'stauts'");
    expect_bad(HEAD "[reg.status]\nwidth = 32\n[reg.alarm]\naddress = 4\n", CFG_ERR_MISSING, 4,
               "reg.status.address", "needs its address");
    expect_bad(HEAD "[reg.status]\nwidth = 32\n", CFG_ERR_MISSING, 4, "reg.status.address", "needs its address");
    expect_bad(HEAD "[reg.status]\naddress = 70000\n", CFG_ERR_RANGE, 5, "reg.status.address", "outside 0..65535");
    expect_bad(HEAD "[reg.status]\naddress = 0x1FFFFFFFF\n", CFG_ERR_VALUE, 5, "reg.status.address",
               "not a register address");
    expect_bad(HEAD "[reg.status]\naddress = 3\naddress = 4\n", CFG_ERR_DUPLICATE, 6, "reg.status.address",
               "set twice");
    expect_bad(HEAD "[reg.status]\naddress = 3\n[reg.status]\naddress = 4\n", CFG_ERR_DUPLICATE, 6, "reg.status",
               "appears twice");
    expect_bad(HEAD "[reg.actual_pos]\naddress = 3\nscale = 0.001\n", CFG_ERR_UNKNOWN, 6, "reg.actual_pos.scale",
               "counts_per_mm");
    expect_bad(HEAD "[info.t]\naddress = 3\ntype = coil\nwidth = 32\n", CFG_ERR_CHECK, 4, "info.t.width",
               "one bit");
    expect_bad(HEAD "[info.a b]\naddress = 3\n", CFG_ERR_VALUE, 4, "info.a b", "letters, digits");
    expect_bad(HEAD "ctl_stop = banana\n", CFG_ERR_VALUE, 4, "map.ctl_stop", "not an integer");
    expect_bad(HEAD "counts_per_mm = -1\n", CFG_ERR_RANGE, 4, "map.counts_per_mm", "outside");
    expect_bad(HEAD "colour = red\n", CFG_ERR_UNKNOWN, 4, "map.colour", "unknown key");
    expect_bad(HEAD "[drive]\n", CFG_ERR_UNKNOWN, 4, "drive", "unknown section");
    expect_bad("[map]\nname = m\n", CFG_ERR_MISSING, 1, "map.verified", "verified = yes | no");
    expect_bad("[map]\nverified = maybe\n", CFG_ERR_VALUE, 2, "map.verified", "not yes or no");
    expect_bad("[reg.status]\naddress = 1\n", CFG_ERR_MISSING, 0, "map", "no [map] section");
}

/* A rail section names a map file relative to its own file; reg_ and scale keys apply on top
   of it whatever their order; a map file's error reaches the rig file's line. */
static void test_rail_section_names_a_file(void **s)
{
    (void)s;
    char dir[] = "/tmp/test_map_file_XXXXXX";
    assert_non_null(mkdtemp(dir));
    char sub[600], map[700], rig[700];
    snprintf(sub, sizeof sub, "%s/maps", dir);
    assert_int_equal(mkdir(sub, 0700), 0);
    snprintf(map, sizeof map, "%s/drive.ini", sub);
    FILE *f = fopen(map, "w");
    assert_non_null(f);
    fputs("[map]\nname = drive\nverified = no\ncounts_per_mm = 0\nctl_stop = 2\nst_moving = 2\n"
          "[reg.target_pos]\naddress = 0\nwidth = 32\n[reg.speed]\naddress = 2\nwidth = 32\n"
          "[reg.trigger]\naddress = 6\n[reg.control]\naddress = 6\n"
          "[reg.actual_pos]\naddress = 8\nwidth = 32\ntype = input\n[reg.status]\naddress = 12\n",
          f);
    fclose(f);
    snprintf(rig, sizeof rig, "%s/rig.ini", dir);
    f = fopen(rig, "w");
    assert_non_null(f);
    fputs("[rail.shear]\ndriver = modbus\ncounts_per_mm = 400\nreg_alarm = 13\nmap = maps/drive.ini\n"
          "watchdog_external = on\n",
          f);
    fclose(f);
    rail_config rc;
    char why[900] = "";
    cfg_status st = rail_config_load(rig, "shear", &rc, why, sizeof why);
    if (st != CFG_OK)
        print_error("%s\n", why);
    assert_int_equal(st, CFG_OK);
    assert_string_equal(rc.modbus.map.name, "drive");
    assert_false(rc.modbus.map.verified);
    assert_true(rc.modbus.map.counts_per_mm == 400.0); /* the rig file's, on top of the map's 0 */
    assert_int_equal(rc.modbus.map.alarm.addr, 13);
    assert_int_equal(rc.modbus.map.actual_pos.kind, RAIL_MB_INPUT);
    assert_string_equal(rc.modbus.map.file, map);

    /* Without counts_per_mm the driver's check names it. */
    f = fopen(rig, "w");
    fputs("[rail.shear]\ndriver = modbus\nmap = maps/drive.ini\n", f);
    fclose(f);
    assert_int_not_equal(rail_config_load(rig, "shear", &rc, why, sizeof why), CFG_OK);
    assert_non_null(strstr(why, "counts_per_mm must be set"));

    /* A broken map file: the rig file's line and key, then the map file's line and key. */
    f = fopen(map, "a");
    fputs("[reg.alarm]\naddress = 13\ntype = eeprom\n", f);
    fclose(f);
    f = fopen(rig, "w");
    fputs("[rail.shear]\ndriver = modbus\n\nmap = maps/drive.ini\n", f);
    fclose(f);
    assert_int_not_equal(rail_config_load(rig, "shear", &rc, why, sizeof why), CFG_OK);
    char want[900];
    snprintf(want, sizeof want, "rig.ini:4: [rail.shear] map: %s:25: reg.alarm.type: 'eeprom' is not", map);
    if (!strstr(why, want)) {
        print_error("'%s' lacks '%s'\n", why, want);
        fail();
    }
    /* A missing map file. */
    f = fopen(rig, "w");
    fputs("[rail.shear]\ndriver = modbus\nmap = maps/none.ini\n", f);
    fclose(f);
    assert_int_not_equal(rail_config_load(rig, "shear", &rc, why, sizeof why), CFG_OK);
    assert_non_null(strstr(why, "rig.ini:3: [rail.shear] map: "));
    assert_non_null(strstr(why, "maps/none.ini"));
    unlink(rig);
    unlink(map);
    rmdir(sub);
    rmdir(dir);
}

/* The whole-rig loader resolves the map file against the rig file's directory (the shipped
   rehearsal rig names maps/ribbon-sim.ini) and blames the map key's line in the rig file. */
static void test_rig_loader_map_file(void **s)
{
    (void)s;
    char path[512];
    snprintf(path, sizeof path, "%s/config/rig-rehearsal-modbus.ini", RIBBON_SOURCE_DIR);
    rig_config *rig = malloc(sizeof *rig);
    assert_non_null(rig);
    cfg_error err;
    cfg_status st = rig_config_load(path, NULL, 0, rig, &err);
    if (st != CFG_OK) {
        char msg[700];
        print_error("%s\n", cfg_error_format(&err, msg, sizeof msg));
    }
    assert_int_equal(st, CFG_OK);
    rail_modbus_map preset;
    assert_int_equal(rail_modbus_preset("ribbon-sim", &preset), RAIL_OK);
    assert_same_map(&rig->shear.modbus.map, &preset);
    assert_same_map(&rig->compress.modbus.map, &preset);
    assert_non_null(strstr(rig->shear.modbus.map.file, "config/maps/ribbon-sim.ini"));
    /* An override naming a missing file fails on the override, not silently. */
    const char *ovr[] = {"rail.shear.map=maps/none.ini"};
    assert_int_not_equal(rig_config_load(path, ovr, 1, rig, &err), CFG_OK);
    char msg[700];
    cfg_error_format(&err, msg, sizeof msg);
    if (!strstr(msg, "maps/none.ini")) {
        print_error("%s\n", msg);
        fail();
    }
    free(rig);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shipped_maps_equal_presets),
        cmocka_unit_test(test_types_and_info),
        cmocka_unit_test(test_bad_files),
        cmocka_unit_test(test_rail_section_names_a_file),
        cmocka_unit_test(test_rig_loader_map_file),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
