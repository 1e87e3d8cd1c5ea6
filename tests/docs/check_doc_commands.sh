#!/bin/sh
# check_doc_commands.sh: the docs check. Every command that README.md and docs/*.md show (in code
# blocks and in `code spans`: ribbonctl, ribbon-sim, ribbond, ribbon-grblsim, ribbon-mbsim,
# ribbon-store-bench, ribbon-fit-family, make) must exist, and its --help must name every --option the docs use
# with it, so docs that drift from the programs fail the build.
#
# usage: check_doc_commands.sh BIN_DIR MAKEFILE DOC.md|DIR ...   (a DIR stands for its *.md, so
#   a page added to docs/ is checked without touching the build)
#   ribbonctl and ribbon-sim take a subcommand (the first word after the program): it must exist
#   (`PROG SUB --help` exits 0) and its help is the one checked. ribbond's one help covers its
#   `ribbond bench` form. A `make X` needs a rule for X in MAKEFILE. Prints one line per problem,
#   FILE:LINE: ..., and exits 1 if there is any.
set -u
if [ $# -lt 3 ]; then
  echo "usage: $0 BIN_DIR MAKEFILE DOC.md ..." >&2
  exit 2
fi
bin=$1 makefile=$2
shift 2
docs=""
for d in "$@"; do
  if [ -d "$d" ]; then
    for f in "$d"/*.md; do [ -e "$f" ] && docs="$docs
$f"; done
  else
    docs="$docs
$d"
  fi
done
set -f # the words of a command are split below, never globbed
IFS_SAVED=$IFS
IFS='
'
# shellcheck disable=SC2086
set -- $docs
IFS=$IFS_SAVED
for f in "$bin/ribbonctl" "$bin/ribbon-sim" "$bin/ribbond" "$makefile"; do
  [ -e "$f" ] || { echo "$0: $f not found" >&2; exit 2; }
done
tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT

# 1. The commands the docs show, one per line: FILE LINE PROGRAM FIRST OPTIONS, \037-separated.
awk -f "$(dirname "$0")/doc_commands.awk" "$@" > "$tmp/commands" || exit 2

# 2. The Makefile's targets.
sed -n 's/^\([A-Za-z0-9_. -][A-Za-z0-9_. -]*\):\([^=].*\)\{0,1\}$/\1/p' "$makefile" |
  tr ' ' '\n' | sed '/^$/d' | sort -u > "$tmp/targets"

# 3. Each command against its program's help (cached per program and subcommand).
helpfile() { # PROG [SUB] -> path of the help text, or empty when the command does not exist
  key=$(printf '%s_%s' "$1" "${2:-}" | tr -c 'A-Za-z0-9_\n-' '_')
  h="$tmp/help.$key"
  if [ ! -e "$h" ] && [ ! -e "$h.missing" ]; then
    if [ -n "${2:-}" ]; then "$bin/$1" "$2" --help > "$h" 2>&1; else "$bin/$1" --help > "$h" 2>&1; fi
    [ $? -eq 0 ] || mv "$h" "$h.missing"
  fi
  [ -e "$h" ] && echo "$h"
}
problems=0
checked=0
sep=$(printf '\037')
while IFS="$sep" read -r file line prog first opts; do
  checked=$((checked + 1))
  where="$file:$line"
  if [ "$prog" = make ]; then
    case "$first" in
      ''|-*|*=*) ;;
      *) grep -qx -- "$first" "$tmp/targets" ||
           { echo "$where: make $first: no such target in $makefile"; problems=$((problems + 1)); } ;;
    esac
    continue
  fi
  if [ ! -x "$bin/$prog" ]; then
    echo "$where: $prog: no such program in $bin"; problems=$((problems + 1)); continue
  fi
  sub=""
  case "$prog" in
    ribbonctl|ribbon-sim)
      case "$first" in [a-z]*) sub=$first ;; esac ;;
  esac
  h=$(helpfile "$prog" "$sub")
  if [ -z "$h" ]; then
    echo "$where: $prog $sub: no such command ('$prog $sub --help' fails)"
    problems=$((problems + 1)); continue
  fi
  if [ "$prog" = ribbond ]; then
    case "$first" in
      [a-z]*) grep -q -- "ribbond $first" "$h" ||
                { echo "$where: ribbond $first: not in 'ribbond --help'"; problems=$((problems + 1)); } ;;
    esac
  fi
  for opt in $opts; do
    [ "$opt" = --help ] && continue
    grep -qE -- "(^|[^a-z0-9-])$opt([^a-z0-9-]|\$)" "$h" ||
      { echo "$where: $prog${sub:+ $sub} $opt: not in '$prog${sub:+ $sub} --help'"; problems=$((problems + 1)); }
  done
done < "$tmp/commands"

if [ "$checked" -eq 0 ]; then
  echo "$0: no commands found in $* (is the extraction broken?)"
  exit 1
fi
if [ "$problems" -gt 0 ]; then
  echo "$problems problem(s) in $checked commands shown by the docs"
  exit 1
fi
echo "docs: $checked commands checked against the programs' --help"
exit 0
