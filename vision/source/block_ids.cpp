// block_ids.cpp: a live camera's block ids followed to count lost frames, and to tell a late
// buffer (delivered after a newer one) from a 16-bit wrap or a restart of the ids. Kept apart from
// source_aravis.cpp so the rule is tested without a camera (tests/vision/test_vision_block_ids.c).
#include "vis_source.h"

// A late buffer is at most this many ids behind the newest: a stream holds tens of buffers, so a
// buffer further back is not late but a wrap (16-bit ids) or the camera's ids starting again.
static const uint64_t LATE_WINDOW = 1024;
static const uint64_t ID16_MAX = 65535; // GigE Vision 1.x: 65535 -> 1, 0 is never used

long vis_block_ids_next(vis_block_ids *ids, uint64_t id)
{
    if (!ids->have) {
        ids->have = 1;
        ids->last = id;
        return 0;
    }
    const uint64_t last = ids->last;
    if (id > last) {
        // Just after a 16-bit wrap, a late buffer from before it looks almost a whole turn ahead.
        if (id <= ID16_MAX && id - last > ID16_MAX - LATE_WINDOW)
            return VIS_BLOCK_LATE;
        ids->last = id;
        return (long)(id - last - 1);
    }
    if (last - id <= LATE_WINDOW)
        return VIS_BLOCK_LATE;
    ids->last = id;
    if (last <= ID16_MAX && id >= 1) // a 16-bit wrap, with the frames lost across it
        return (long)((ID16_MAX - last) + (id - 1));
    return 0; // 64-bit ids far back: the camera started its ids again; nothing known lost
}
