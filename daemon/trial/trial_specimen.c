/* trial_specimen.c: the specimen record (store) a rig file describes: its [specimen] section and
 * the scene's geometry and material. */
#include "trial_specimen.h"

#include <stdio.h>

void trial_specimen_from_config(const rig_config *cfg, store_specimen *sp)
{
    *sp = store_specimen_default();
    snprintf(sp->name, sizeof sp->name, "%s", cfg->specimen.name[0] ? cfg->specimen.name : "unnamed");
    sp->length_m = cfg->scene.length;
    sp->width_m = cfg->scene.width;
    sp->thickness_m = cfg->scene.thickness;
    sp->youngs_modulus_pa = cfg->scene.youngs_modulus;
    sp->density_kg_m3 = cfg->scene.density;
    snprintf(sp->material, sizeof sp->material, "%.31s", cfg->specimen.material);
    sp->crease_angle_left_deg = cfg->specimen.crease_angle_left_deg;
    sp->crease_angle_right_deg = cfg->specimen.crease_angle_right_deg;
    sp->fold_position = cfg->scene.fold_position;
    snprintf(sp->crease_orientation, sizeof sp->crease_orientation, "%s",
             cfg->specimen.crease_orientation == RIG_CREASE_UP     ? "up"
             : cfg->specimen.crease_orientation == RIG_CREASE_DOWN ? "down"
                                                                   : "");
}
