/* campaign.h: the campaign room's face (issue 35): specimens as records a trial names, and the
 * queue of trials, operator steps and pauses that runs them (docs/campaign.md).
 *   campaign_specimen.h  a specimen through the API, and the rig-file keys a trial of it sets
 *   campaign_operator.h  an operator step's form and the check of its confirmation
 *   campaign_queue.h     the queue's thread and its operations
 *   campaign_routes.h    the /specimens, /queue, /campaign/phase and /plan routes
 *   campaign_edge.h      the boundary the experiments support at one phi (bracket, probit)
 *   campaign_predicted.h the predicted boundary Gamma*(phi): ribbon-sim boundary's CSV or a cached trace
 *   campaign_trace.h     that trace off the API thread (ribbond's GET /campaign/phase: 503 meanwhile)
 *   campaign_phase.h     the lab's phase diagram from the store: counts, edges, CSV, JSON, figure
 *   campaign_plan.h      the next specimens: beliefs with a fitted systematic offset, proposals
 *   campaign_strip.h     the lab strip: the specimens' fitted strips pooled, the planner's model
 *   campaign_bench.h     the simulated campaign: the planner against a bench of twins
 *   campaign_camera_bench.h the same through the camera: approvals, the queue, mock trials
 * Everything outside this folder includes this header only. */
#ifndef RIBBON_CAMPAIGN_H
#define RIBBON_CAMPAIGN_H

#include "campaign_specimen.h"
#include "campaign_operator.h"
#include "campaign_queue.h"
#include "campaign_routes.h"
#include "campaign_edge.h"
#include "campaign_predicted.h"
#include "campaign_trace.h"
#include "campaign_phase.h"
#include "campaign_plan.h"
#include "campaign_strip.h"
#include "campaign_bench.h"
#include "campaign_camera_bench.h"

#endif
