#!/usr/bin/env bash
# Decode speed in the browser: for each mesh, tomstreambench (native) writes its stream and the
# meshoptimizer reference blocks of the same mesh, then headless chromium opens the site's
# bench.html, which decodes both (the wasm runtime; meshoptimizer's npm decoder) and reports
# medians. Prints one JSON object per mesh with the native and the browser figures; writes them
# to out/stream/web.jsonl (scripts/bench-stream.sh puts them in docs/PERFORMANCE.md).
# Usage: scripts/bench-web.sh [MESH...]   (default: bunny00)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
tools="$root/build/tools"
[ -x "$tools/tomstreambench" ] || "$root/scripts/build.sh"
[ -f "$root/data/meshes/bunny00.off" ] || "$root/scripts/fetch-samples.sh"
bash "$root/scripts/build-web.sh" >&2
meshes=("$@")
[ ${#meshes[@]} -gt 0 ] || meshes=("$root/data/meshes/bunny00.off")
out="$root/out/stream"; mkdir -p "$out"
work="$(mktemp -d)"
server=""
cleanup() { [ -z "$server" ] || kill "$server" 2>/dev/null || true; rm -rf "$work"; }
trap cleanup EXIT
node "$root/samples/web/server.mjs" --port 0 --mount "/bench=$work/ref" --report "$work/report.json" "$root/build-web/site" > "$work/server.log" &
server=$!
until grep -q "serving" "$work/server.log"; do sleep 0.2; done
port="$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$work/server.log")"
: > "$out/web.jsonl"
for mesh in "${meshes[@]}"; do
  name="$(basename "${mesh%.*}")"
  "$tools/tombuild" "$mesh" -o "$work/plain" -q --force
  native="$("$tools/tomstreambench" "$work/plain/$name.tom" --json -r 7 --reference-out "$work/ref")"
  rm -f "$work/report.json"
  chromium --headless=new --no-sandbox --user-data-dir="$work/profile" \
    "http://127.0.0.1:$port/bench.html?reference=/bench/$name.meshopt.json&repeats=21&report=1" > /dev/null 2>&1 &
  browser=$!
  for _ in $(seq 600); do [ -s "$work/report.json" ] && break; sleep 0.2; done
  kill "$browser" 2>/dev/null || true; pkill -f "user-data-dir=$work/profile" || true
  [ -s "$work/report.json" ] || { echo "bench-web: no figures from the browser for $name" >&2; exit 1; }
  /usr/bin/python3 -c "
import json, sys
native, browser = json.loads(sys.argv[1]), json.load(open(sys.argv[2]))
if 'error' in browser: sys.exit('bench-web: ' + browser['error'])
print(json.dumps({'mesh': sys.argv[3], 'native': native, 'browser': browser}))" "$native" "$work/report.json" "$name" | tee -a "$out/web.jsonl"
done
