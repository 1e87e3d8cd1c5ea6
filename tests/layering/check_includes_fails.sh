#!/bin/sh
# check_includes_fails.sh: check_includes can fail. In a temporary copy of the tree's sources,
# each of ten bad includes is injected on its own and check_includes must exit 1 naming it:
# a climb across floors, a room's private header from outside, a header declaring another
# file's function, and two headers that include each other; then the same inside vision/ (a
# climb to vision.h, a room of the same step, a private header, a face declaring another room's
# function, a loop) and vision's C++ from outside it. Usage: check_includes_fails.sh
# CHECK_INCLUDES SOURCE_ROOT
set -u
check=$1
src=$2
tmp=$(mktemp -d "${TMPDIR:-/tmp}/check-includes.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT INT TERM
failures=0

fresh() {
    rm -rf "$tmp/tree"
    mkdir -p "$tmp/tree"
    for d in config drivers daemon sim vision; do
        cp -R "$src/$d" "$tmp/tree/$d" || exit 1
    done
}

# expect NAME PATTERN: check_includes on the copy exits 1 and prints a line matching PATTERN.
expect() {
    "$check" "$tmp/tree" >"$tmp/out" 2>&1
    rc=$?
    if [ "$rc" -ne 1 ] || ! grep -q "$2" "$tmp/out"; then
        echo "FAIL: $1: exit $rc, no line matching '$2' in:"
        cat "$tmp/out"
        failures=$((failures + 1))
    else
        echo "ok: $1: $(grep "$2" "$tmp/out" | head -n 1)"
    fi
}

# 1. drivers/ reaching up into the daemon.
fresh
printf '#include "rig_daemon.h"\n' >>"$tmp/tree/drivers/rail.c"
expect "climb" 'drivers/rail.c:[0-9]*: includes daemon/rig_daemon.h: drivers (floor 0) may not include daemon (floor 10)'

# 2. the report reaching past the plot room's face.
fresh
printf '#include "plot_style.h"\n' >>"$tmp/tree/daemon/report/trial_report.c"
expect "private header" 'daemon/report/trial_report.c:[0-9]*: includes daemon/plot/plot_style.h, a private header of daemon/plot'

# 3. a header declaring a function another file defines (rail_mock_open is rail_mock.c's).
fresh
printf 'rail_err rail_mock_open(rail **out, const rail_params *p, const rail_mock_params *m,\n    rail_clock clock, char *why, size_t why_len);\n' >>"$tmp/tree/drivers/rail_pair.h"
expect "ownership" 'drivers/rail_pair.h: declares rail_mock_open(), which drivers/rail_mock.c defines'

# 4. two headers of one room that include each other.
fresh
printf '#include "rail_pair.h"\n' >>"$tmp/tree/drivers/rail_axis.h"
printf '#include "rail_axis.h"\n' >>"$tmp/tree/drivers/rail_pair.h"
expect "loop" 'include loop: .*drivers/rail_axis.{c,h} -> drivers/rail_pair.{c,h}\|include loop: .*drivers/rail_pair.{c,h} -> drivers/rail_axis.{c,h}'

# vision/'s rooms (issue 34 G).
# 5. a vision room reaching up to the umbrella face above every room.
fresh
printf '#include "vision.h"\n' >>"$tmp/tree/vision/track/tracker.cpp"
expect "vision climb" 'vision/track/tracker.cpp:[0-9]*: includes vision/vision.h: vision/track (floor 0.3) may not include vision (floor 0.4)'

# 6. a room reaching for a room on its own step (video and source stand side by side).
fresh
printf '#include "vis_video.h"\n' >>"$tmp/tree/vision/source/source_synth.cpp"
expect "vision same step" 'vision/source/source_synth.cpp:[0-9]*: includes vision/video/vis_video.h: vision/source (floor 0.2) may not include vision/video (floor 0.2)'

# 7. the tracker reaching past the renderer's face for its private camera model.
fresh
printf '#include "camera_model.hpp"\n' >>"$tmp/tree/vision/track/overlay.cpp"
expect "vision private header" 'vision/track/overlay.cpp:[0-9]*: includes vision/render/camera_model.hpp, a private header of vision/render'

# 8. the daemon reaching into vision's C++ (a face inside vision/, not outside it).
fresh
printf '#include "source.hpp"\n' >>"$tmp/tree/daemon/twin/twin_camera.c"
expect "vision C++ from outside" 'daemon/twin/twin_camera.c:[0-9]*: includes vision/source/source.hpp, C++ inside vision/source'

# 9. a room's face declaring another room's function (vis_calib_check is calib.cpp's), inside
# its extern "C" block.
fresh
sed 's/^vis_status vis_source_read(/vis_status vis_calib_check(const vis_calib *c, vis_error *err);\n&/' \
    "$src/vision/source/vis_source.h" >"$tmp/tree/vision/source/vis_source.h"
expect "vision ownership" 'vision/source/vis_source.h: declares vis_calib_check(), which vision/calib/calib.cpp defines, in another room'

# 10. a loop inside a room: the tracker's face and its stages' header including each other.
fresh
printf '#include "tracker_impl.hpp"\n' >>"$tmp/tree/vision/track/vis_track.h"
expect "vision loop" 'include loop: .*vision/track/vis_track.h -> vision/track/tracker_impl.{c,h}\|include loop: .*vision/track/tracker_impl.{c,h} -> vision/track/vis_track.h'

[ "$failures" -eq 0 ]
