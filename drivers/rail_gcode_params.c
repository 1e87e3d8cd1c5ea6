/* rail_gcode_params.c: the G-code rail's default parameters (rail_gcode_params.h). */
#include "rail_gcode_params.h"

#include <string.h>

rail_gcode_params rail_gcode_params_default(void)
{
    rail_gcode_params g;
    memset(&g, 0, sizeof g);
    g.baud = 115200;
    g.axis = 'X';
    g.segment_s = 0.3;
    g.segments_ahead = 2;
    g.reply_timeout_s = 0.2;
    g.stall_timeout_s = 1.0;
    g.min_segment_mm = 0.05;
    g.boot_wait_s = 2.5;
    return g;
}
