#!/bin/sh
# test_doc_drift.sh: the docs check fails on docs that drift from the programs. Runs
# check_doc_commands.sh on fixtures: the control page passes; each drifted page (an unknown option
# in a code span, on a usage text's wrapped line, in a fenced block after a `\` line, in a table
# cell, on the continued line of a prompted command; an unknown subcommand; an unknown make
# target; an unknown ribbond form) fails, naming the line and what drifted.
# usage: test_doc_drift.sh BIN_DIR MAKEFILE
set -u
here=$(dirname "$0")
check="$here/check_doc_commands.sh"
fx="$here/fixtures"
bin=$1 makefile=$2
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

out=$(sh "$check" "$bin" "$makefile" "$fx/good.md" 2>&1) || fail "good.md refused: $out"
case "$out" in *"docs: 10 commands checked"*) ;; *) fail "good.md: expected 10 commands, got: $out" ;; esac

expect() { # FIXTURE TEXT: the check fails on FIXTURE and its report contains TEXT
  out=$(sh "$check" "$bin" "$makefile" "$fx/$1" 2>&1)
  rc=$?
  [ "$rc" -eq 1 ] || fail "$1: exit status $rc, expected 1 (output: $out)"
  case "$out" in *"$2"*) ;; *) fail "$1: report lacks '$2': $out" ;; esac
}
expect drift-option.md  "drift-option.md:3: ribbonctl start --bogus-flag: not in 'ribbonctl start --help'"
expect drift-wrapped.md "drift-wrapped.md:3: ribbonctl track --no-such-option: not in 'ribbonctl track --help'"
expect drift-fenced.md  "drift-fenced.md:4: ribbon-sim sweep --resolution: not in 'ribbon-sim sweep --help'"
expect drift-table.md   "drift-table.md:5: ribbon-grblsim --turbo: not in 'ribbon-grblsim --help'"
expect drift-session.md "drift-session.md:3: ribbon-sim continue --bogus: not in 'ribbon-sim continue --help'"
expect drift-command.md "drift-command.md:3: ribbon-sim frobnicate: no such command"
expect drift-make.md    "drift-make.md:3: make deploy: no such target"
expect drift-ribbond.md "drift-ribbond.md:3: ribbond calibrate: not in 'ribbond --help'"

# Only what drifted is reported: one problem per drifted page.
out=$(sh "$check" "$bin" "$makefile" "$fx/drift-wrapped.md" 2>&1)
case "$out" in *"1 problem(s) in 1 commands"*) ;; *) fail "drift-wrapped.md: expected 1 problem: $out" ;; esac

[ "$failures" -eq 0 ] && echo "docs drift: every drifted fixture fails, the control passes"
exit "$failures"
