/* fuzz_scene_ini.c: fuzz target for scene files through the real loader (config/scene_file.c on
 * text in memory): a refusal names a status and a message; an accepted scene passes the
 * simulator's own cross-checks and holds only finite numbers. */
#include <math.h>
#include <string.h>

#include "fuzz_inputs.h"
#include "fuzz_config.h"
#include "scene_file.h"

void fuzz_check_scene(const char *who, const rod_scene *s)
{
    const double v[] = {s->length,      s->width,       s->thickness,  s->youngs_modulus,
                        s->shear_modulus, s->density,   s->fold_angle_deg, s->fold_position,
                        s->compression, s->shear_rate,  s->shear_max,  s->dt,
                        s->damping,     s->tolerance,   s->snap_speed, s->asym_threshold,
                        s->fold_stiffness_factor, s->fold_angle_rel, s->gravity[0], s->gravity[1],
                        s->gravity[2]};
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
        if (!isfinite(v[i])) fuzz_fail(who, "an accepted scene holds a non-finite value");
    char msg[256], key[96];
    if (rod_scene_check(s, msg, sizeof msg, key, sizeof key) != 0)
        fuzz_fail(who, "an accepted scene fails rod_scene_check");
}

int fuzz_scene_ini_one(const uint8_t *data, size_t size)
{
    rod_scene s;
    cfg_error err;
    cfg_status st = cfg_scene_parse("fuzz.ini", (const char *)data, size, NULL, 0, &s, &err);
    if (st == CFG_OK) {
        fuzz_check_scene("scene_ini", &s);
    } else {
        char line[1024];
        if (err.status != st || err.message[0] == '\0') fuzz_fail("scene_ini", "a refusal without a reason");
        cfg_error_format(&err, line, sizeof line);
        if (strlen(line) == 0) fuzz_fail("scene_ini", "an empty formatted error");
    }
    return 0;
}

FUZZ_ENTRY(fuzz_scene_ini_one)
