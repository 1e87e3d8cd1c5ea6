#!/bin/sh
# test_install_staged.sh: `cmake --install` into a staging directory (DESTDIR), then a mock trial
# from the installed programs and files only. Checks the layout (programs in bin/, rig files and
# scenes in share/ribbon/, the unit in lib/systemd/system/ naming the prefix, nothing in etc/ or
# var/, the unit not enabled), that no installed file names a path into the source or build tree
# (other than the names of source files, .c .cpp .h .hpp, in assertion messages), then runs
# ribbond on the installed mock.ini from an empty working directory and `ribbonctl start --wait`
# against it. Where a mount namespace is available (unshare, as root), the trial runs with the
# source and build trees hidden under empty tmpfs mounts, so a read from either fails.
#
# usage: test_install_staged.sh BUILD_DIR SOURCE_DIR [LSAN_SUPPRESSIONS]
# The trial is cut short to stay quick in both builds: N = 31 (the twin's [twin] strip and the
# prediction), 60 frames per second at 320 x 240 (the asymmetric passage of the snap lasts
# 20-25 ms: at 10 fps the measured regime missed it), short hold and post-snap times.
set -u

if [ "${1:-}" = --trial ]; then
  # The trial itself: STAGE RUN_DIR (with the trees already hidden, when they can be).
  stage=$2 run=$3
  cd "$run" || exit 1
  bin="$stage/usr/bin"
  "$bin/ribbond" --config "$stage/usr/share/ribbon/mock.ini" --set api.port=0 \
    --set sim.nodes=31 --set sim.dt=0.004 --set twin.mesh.nodes=31 --set twin.solver.dt=0.004 \
    --set camera.fps=60 --set camera.width_px=320 \
    --set camera.height_px=240 --set trial.hold_s=0.5 --set trial.post_snap_s=0.5 \
    2> ribbond.log &
  pid=$!
  url=""
  i=0
  while [ $i -lt 600 ]; do
    url=$(sed -n 's/.*listening on \(http[^ ]*\).*/\1/p' ribbond.log)
    [ -n "$url" ] && break
    kill -0 $pid 2>/dev/null || break
    sleep 0.1
    i=$((i + 1))
  done
  if [ -z "$url" ]; then
    echo "FAIL: the installed ribbond did not start:"; cat ribbond.log
    kill $pid 2>/dev/null
    exit 1
  fi
  "$bin/ribbonctl" start --url "$url" --note "staged install" --wait --out report.png > start.out 2>&1
  rc=$?
  kill -TERM $pid
  wait $pid
  drc=$?
  cat start.out
  [ $rc -eq 0 ] || { echo "FAIL: ribbonctl start --wait exited $rc"; cat ribbond.log; exit 1; }
  [ $drc -eq 0 ] || { echo "FAIL: ribbond exited $drc on SIGTERM"; cat ribbond.log; exit 1; }
  exit 0
fi

build=$1 src=$2 supp=${3:-}
tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT
stage="$tmp/stage" run="$tmp/run"
mkdir -p "$run"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# --- install
# --strip, as the package's files are: debug information names the build tree.
DESTDIR="$stage" cmake --install "$build" --prefix /usr --strip > "$tmp/install.log" 2>&1 ||
  { cat "$tmp/install.log"; echo "FAIL: cmake --install"; exit 1; }

# --- layout
for p in ribbond ribbonctl ribbon-sim ribbon-grblsim ribbon-mbsim ribbon-store-bench; do
  [ -x "$stage/usr/bin/$p" ] || fail "usr/bin/$p not installed"
done
for f in mock.ini replay.ini rig-gcode.ini rig-modbus.ini scenes/mock-gamma013.ini \
         scenes/paper-gamma013.ini scenes/paper-gamma021.ini scenes/pet-200x5.ini \
         maps/ribbon-sim.ini maps/oriental-az.ini; do
  [ -f "$stage/usr/share/ribbon/$f" ] || fail "usr/share/ribbon/$f not installed"
done
unit="$stage/usr/lib/systemd/system/ribbond.service"
if [ -f "$unit" ]; then
  grep -qx 'ExecStart=/usr/bin/ribbond --config /etc/ribbon/rig.ini' "$unit" ||
    fail "the installed unit's ExecStart does not name /usr/bin/ribbond: $(grep ExecStart "$unit")"
  grep -qx 'StateDirectory=ribbon' "$unit" || fail "the installed unit lost StateDirectory=ribbon"
  grep -q '/usr/local' "$unit" && fail "the installed unit still names /usr/local"
else
  fail "usr/lib/systemd/system/ribbond.service not installed"
fi
[ -f "$stage/usr/lib/sysusers.d/ribbon.conf" ] || fail "usr/lib/sysusers.d/ribbon.conf not installed"
[ -f "$stage/usr/share/doc/ribbon/README.md" ] || fail "usr/share/doc/ribbon/README.md not installed"
[ -f "$stage/usr/share/doc/ribbon/docs/install.md" ] || fail "usr/share/doc/ribbon/docs/install.md not installed"
# Nothing outside the prefix: no /etc (the lab's rig file, an enabled unit), no /var.
for d in etc var; do
  [ -e "$stage/$d" ] && fail "the install wrote $d/: $(find "$stage/$d" | head -3)"
done

# --- no path into the source or build tree, except source file names (__FILE__ in assertions)
for f in $(find "$stage" -type f ! -name '*.png'); do
  for tree in "$src" "$build"; do
    tr -c '[:print:]' '\n' < "$f" | grep -F "$tree" | grep -Ev "^[^ ]*$tree/[^ ]*\.(c|cpp|h|hpp)$" |
      head -3 > "$tmp/paths"
    [ -s "$tmp/paths" ] && fail "${f#"$stage"} names the tree: $(cat "$tmp/paths")"
  done
done

# --- a mock trial from the installed files, from an empty working directory
if [ -n "$supp" ] && [ -f "$supp" ]; then
  cp "$supp" "$tmp/lsan.supp"
  LSAN_OPTIONS="suppressions=$tmp/lsan.supp:print_suppressions=0"
  export LSAN_OPTIONS
fi
cp "$0" "$tmp/trial.sh"
hidden=no
# shellcheck disable=SC2016
if unshare --mount --propagation private true 2>/dev/null; then
  unshare --mount --propagation private sh -c '
    mount -t tmpfs ribbon-hidden "$2" && mount -t tmpfs ribbon-hidden "$1" &&
    [ -z "$(ls -A "$1")" ] && exec sh "$3" --trial "$4" "$5"' sh "$src" "$build" \
    "$tmp/trial.sh" "$stage" "$run" > "$tmp/trial.out" 2>&1
  rc=$?
  hidden=yes
else
  sh "$tmp/trial.sh" --trial "$stage" "$run" > "$tmp/trial.out" 2>&1
  rc=$?
fi
cat "$tmp/trial.out"
[ $rc -eq 0 ] || fail "the mock trial from the installed files failed (trees hidden: $hidden)"
out=$(cat "$tmp/trial.out")
for want in "trial 1: done" "measured   snap Delta W = 0." "predicted  snap Delta W = 0.4" \
            "twin truth snap Delta W = 0." \
            "report: report.png" "database: $run/ribbon-mock.db"; do
  case "$out" in *"$want"*) ;; *) fail "ribbonctl's output lacks '$want'" ;; esac
done
# (each by its own line: the calibrated prediction's line says its regime too)
for who in "measured   snap" "predicted  snap" "twin truth snap"; do
  grep -q "^  $who Delta W = .*regime asymmetric" "$tmp/trial.out" ||
    fail "measured, predicted and the twin's true regimes are not all asymmetric ($who)"
done
[ "$(head -c 4 "$run/report.png" 2>/dev/null | tail -c 3)" = PNG ] || fail "no report PNG"
[ -d "$run/ribbon-mock-videos" ] || fail "no video directory in the working directory"

if [ "$failures" -eq 0 ]; then
  echo "staged install: layout ok, no tree paths, mock trial done (source and build trees hidden: $hidden)"
fi
exit "$failures"
