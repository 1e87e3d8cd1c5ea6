#!/bin/sh
# bench_snap_stop.sh: the snap-to-stop latency of short rig trials on loopback (issue 34 F).
# Runs N trials (ribbon-rigsim + ribbond on RIG, compression at 20 mm/s so each reaches shearing
# in about 7 s: about 30 s a trial), one at a time (the simulated camera takes GVCP port 3956),
# and prints per trial one JSON line from snap_stop_breakdown.py with the load average at its
# start, then one summary line:
#   {"bench":"snap_stop","rig":...,"n":...,"det_to_read_ms":{"median":..,"max":..},
#    "target_ms":...,"bound_ms":...,"load":[..]}
# target_ms is the issue's (two frame periods plus one poll), bound_ms the physical one
# (docs/rig-realtime.md "Snap to stop": two frame periods + v/a + the stop watch's pass + 10 ms).
# Usage: bench_snap_stop.sh BUILD_DIR RIG.ini [N] (from the checkout; keeps the runs' stores and
# logs in /tmp/snap-stop.XXXXXX, printed on stderr; their raw videos only with
# RIBBON_BENCH_KEEP_VIDEO=1).
set -u
build=${1:?build dir}; rig=${2:?rig file}; n=${3:-3}
here=$(cd "$(dirname "$0")" && pwd)
out=$(mktemp -d /tmp/snap-stop.XXXXXX); echo "runs in $out" >&2
lines=""
i=0
while [ "$i" -lt "$n" ]; do
    i=$((i + 1)); d=$out/run$i; mkdir -p "$d"
    load=$(cut -d' ' -f1 /proc/loadavg)
    case "$(grep -c '^driver *= *modbus' "$rig")" in
    0) sets="--set rail.compress.port=$d/grbl --set rail.shear.port=$d/grbl" ;;
    *) p1=$((20000 + $$ % 20000 + 2 * i)); sets="--set rail.compress.address=127.0.0.1:$p1 --set rail.shear.address=127.0.0.1:$((p1 + 1))" ;;
    esac
    sets="$sets --set camera.calibration=$d/camera.calib --set store.path=$d/rig.db --set camera.video_dir=$d/videos"
    sets="$sets --set trial.compress_speed_mm_s=20 --set camera.transcode=off"
    # shellcheck disable=SC2086
    "$build/bin/ribbon-rigsim" "$rig" $sets --truth "$d/truth.csv" --axes-log "$d/axes.csv" >"$d/rigsim.out" 2>&1 &
    sim=$!
    k=0; while [ $k -lt 300 ] && ! grep -q '^ready' "$d/rigsim.out"; do kill -0 $sim 2>/dev/null || break; sleep 0.1; k=$((k + 1)); done
    # shellcheck disable=SC2086
    "$build/bin/ribbond" --config "$rig" $sets 2>"$d/ribbond.err" &
    dmn=$!
    url=""; k=0
    while [ $k -lt 300 ] && [ -z "$url" ]; do
        url=$(sed -n 's/.*listening on \(http[^ ]*\).*/\1/p' "$d/ribbond.err"); kill -0 $dmn 2>/dev/null || break; sleep 0.1; k=$((k + 1))
    done
    [ -n "$url" ] && "$build/bin/ribbonctl" start --url "$url" --note bench --wait >"$d/trial.txt" 2>&1
    kill -TERM $dmn 2>/dev/null; wait $dmn 2>/dev/null
    kill -TERM $sim 2>/dev/null; wait $sim 2>/dev/null
    v=$(sed -n 's/^shear_rate *= *\([0-9.e-]*\).*/\1/p' "$(dirname "$rig")/$(sed -n 's/^scene *= *//p' "$rig" | head -1)" | head -1)
    a=$(awk '/^\[rail.shear\]/{s=1} s && /^accel_mm_s2/{print $3; exit}' "$rig")
    line=$(python3 "$here/snap_stop_breakdown.py" "$d/rig.db" "$d/truth.csv" "$d/axes.csv" --label "run$i load $load" \
        --v "$(awk -v r="$v" 'BEGIN{print r * 1000}')" --a "$a")
    echo "$line"
    [ -n "${RIBBON_BENCH_KEEP_VIDEO:-}" ] || rm -rf "$d/videos" # ~0.4 GB of raw video a trial
    lines="$lines$line
"
done
printf '%s' "$lines" | python3 -c '
import json, sys, statistics
rig, fps, hz, v, a = sys.argv[1], 60.0, 20.0, 10.0, 200.0
rows = [json.loads(l) for l in sys.stdin if l.strip()]
tot = [r["det_to_read"] for r in rows if r.get("det_to_read") is not None]
loads = [float(r["label"].split()[-1]) for r in rows]
s = {"bench": "snap_stop", "rig": rig, "n": len(rows), "ok": len(tot),
     "det_to_read_ms": {"median": statistics.median(tot) if tot else None, "max": max(tot) if tot else None},
     "target_ms": round(2e3 / fps + 1e3 / hz, 1), "bound_ms": round(2e3 / fps + 1e3 * v / a + 5.0 + 10.0, 1),
     "load": loads}
print(json.dumps(s))' "$rig"
