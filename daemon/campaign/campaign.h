/* campaign.h: the campaign room's face (issue 35): specimens as records a trial names, and the
 * queue of trials, operator steps and pauses that runs them (docs/campaign.md).
 *   campaign_specimen.h  a specimen through the API, and the rig-file keys a trial of it sets
 *   campaign_operator.h  an operator step's form and the check of its confirmation
 *   campaign_queue.h     the queue's thread and its operations
 *   campaign_routes.h    the /specimens and /queue routes
 * Everything outside this folder includes this header only. */
#ifndef RIBBON_CAMPAIGN_H
#define RIBBON_CAMPAIGN_H

#include "campaign_specimen.h"
#include "campaign_operator.h"
#include "campaign_queue.h"
#include "campaign_routes.h"

#endif
