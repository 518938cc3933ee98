#!/usr/bin/env bash
# Instructions per object per frame of one libtcr selector, counted by valgrind's callgrind
# (repeatable on a shared machine, unlike wall time).
# usage: scripts/tcrbench-instructions.sh [SELECTOR=exact] [OBJECTS=10000] [FRAMES=10] [extra tcrbench options...]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
selector="${1:-exact}"; objects="${2:-10000}"; frames="${3:-10}"; shift $(( $# < 3 ? $# : 3 ))
out="$(mktemp)"; trap 'rm -f "$out"' EXIT
valgrind --tool=callgrind --callgrind-out-file="$out" --toggle-collect='tcr::select(*' \
  "$root/build/tools/tcrbench" --selector "$selector" --objects "$objects" --frames "$frames" --json "$@" >/dev/null 2>&1
ir=$(callgrind_annotate "$out" 2>/dev/null | awk '/PROGRAM TOTALS/ {gsub(",", "", $1); print $1; exit}')
echo "$selector: $ir instructions in tcr::select over $frames frames of $objects objects = $(( ir / (objects * frames) )) per object per frame"
