#!/bin/sh
# check_includes_fails.sh: check_includes can fail. In a temporary copy of the tree's sources,
# each of four bad includes is injected on its own and check_includes must exit 1 naming it:
# a climb across floors, a room's private header from outside, a header declaring another
# file's function, and two headers that include each other. Usage: check_includes_fails.sh
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

[ "$failures" -eq 0 ]
