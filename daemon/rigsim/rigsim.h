/* rigsim.h: the face of the rig simulator's room (daemon/rigsim/): the rig's hardware in one
 * process for ribbon-rigsim, the GRBL controller (rigsim_rails.h) and the GigE Vision camera
 * filming the twin (rigsim_camera.h). Everything outside this folder includes this header only. */
#ifndef RIBBON_RIGSIM_H
#define RIBBON_RIGSIM_H

#include "rigsim_rails.h"
#include "rigsim_camera.h"

#endif
