/* trial_specimen.h: the specimen a rig file describes, as the store keeps it (trial_specimen.c). */
#ifndef RIBBON_TRIAL_SPECIMEN_H
#define RIBBON_TRIAL_SPECIMEN_H

#include "rig_config.h"
#include "store.h"

void trial_specimen_from_config(const rig_config *cfg, store_specimen *sp);

#endif
