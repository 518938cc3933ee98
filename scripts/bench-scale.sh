#!/usr/bin/env bash
# Conversion at scale, measured: a generated mesh of TRIANGLES triangles (default 10M) written
# as binary PLY, then
#  - tombench's build against meshopt_simplify to 1% in the same run;
#  - tombuild's conversion of the PLY with and without the error curve: seconds per stage
#    (import, build, error curve, write) and peak memory (GNU time's maximum resident set);
#  - the report (--report-json) of a REPORT_TRIANGLES mesh (default 2M): its peak memory; with
#    --large-report, the report of the TRIANGLES mesh too (about 8 minutes at 10M);
#  - a batch over data/ converted once and rerun unchanged: the rerun's share of the first run.
# Prints a Markdown table (scripts/bench.sh --scale puts it in docs/PERFORMANCE.md) and, with
# --json, one JSON object instead.
# Usage: scripts/bench-scale.sh [--json] [--large-report] [TRIANGLES [REPORT_TRIANGLES]]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
json=0; large=0
while [ $# -gt 0 ]; do
  case "$1" in
    --json) json=1; shift ;;
    --large-report) large=1; shift ;;
    *) break ;;
  esac
done
triangles="${1:-10000000}"; report_triangles="${2:-2000000}"
tools="$root/build/tools"
[ -x "$tools/tombuild" ] || "$root/scripts/build.sh" >&2
[ -f "$root/data/meshes/bunny00.off" ] || "$root/scripts/fetch-samples.sh" >&2
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT

# convert LABEL INPUT [tombuild options]: "seconds import build curve write peak_kb" into $work/LABEL
convert() {
  local label="$1" input="$2"; shift 2
  /usr/bin/time -f "%e %M" -o "$work/$label.time" "$tools/tombuild" "$input" -o "$work/out-$label" -v --no-isolate --force "$@" > "$work/$label.log"
  local stages
  stages=$(sed -n 's/.*seconds: import \([0-9.]*\), build \([0-9.]*\), error curve and report \([0-9.]*\), write \([0-9.]*\)/\1 \2 \3 \4/p' "$work/$label.log")
  read -r seconds peak < "$work/$label.time"
  echo "$seconds $stages $peak" > "$work/$label"
}

echo "bench-scale: generating $triangles triangles" >&2
"$tools/tombench" --generated "$triangles" --write-generated "$work/large.ply"
"$tools/tombench" --generated "$report_triangles" --write-generated "$work/report.ply"
echo "bench-scale: tombench against meshopt_simplify" >&2
"$tools/tombench" --generated "$triangles" --json -r 1 > "$work/tombench.json"
echo "bench-scale: conversions" >&2
convert curve "$work/large.ply"
convert nocurve "$work/large.ply" --no-error-curve
convert report "$work/report.ply" --report-json "$work/reports"
[ $large = 1 ] && convert large_report "$work/large.ply" --report-json "$work/large-reports"
echo "bench-scale: a batch and its rerun" >&2
/usr/bin/time -f "%e" -o "$work/first.time" "$tools/tombuild" "$root/data" -o "$work/batch" -j 2 -q 2>/dev/null || true
/usr/bin/time -f "%e" -o "$work/rerun.time" "$tools/tombuild" "$root/data" -o "$work/batch" -j 2 -q 2>/dev/null || true
inputs=$(wc -l < "$work/batch/manifest.jsonl")

/usr/bin/python3 - "$work" "$triangles" "$report_triangles" "$inputs" "$json" "$large" <<'PY'
import json, sys
work, triangles, report_triangles, inputs, as_json = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5] == "1"
large = sys.argv[6] == "1"
def run(label):
    seconds, imp, build, curve, write, peak = open(f"{work}/{label}").read().split()
    return {"seconds": float(seconds), "import": float(imp), "build": float(build), "curve": float(curve), "write": float(write), "peak_bytes": int(peak) * 1024}
bench = json.loads(open(f"{work}/tombench.json").read().splitlines()[0])
# (GNU time says "Command exited with non-zero status 1" first: data/ holds broken glTF on purpose)
first, rerun = (float(open(f"{work}/{t}.time").read().split()[-1]) for t in ("first", "rerun"))
out = {"triangles": triangles, "build_over_meshopt": bench["build_ms"] / bench["meshopt_ms"], "build_ms": bench["build_ms"], "meshopt_ms": bench["meshopt_ms"],
       "with_curve": run("curve"), "without_curve": run("nocurve"), "report_triangles": report_triangles, "report": run("report"),
       "batch_inputs": inputs, "batch_first_seconds": first, "batch_rerun_seconds": rerun}
if large:
    out["large_report"] = run("large_report")
if as_json:
    print(json.dumps(out))
    sys.exit(0)
c, n, r = out["with_curve"], out["without_curve"], out["report"]
flag = " --large-report" if large else ""
print(f"A generated sphere of {triangles:,} triangles as binary PLY (`scripts/bench-scale.sh{flag} {triangles} {report_triangles}`):\n")
print("| measure | figure |\n|---|---|")
print(f"| build / meshopt_simplify to 1% (tombench, same run) | {out['build_over_meshopt']:.2f}x ({bench['build_ms'] / 1000:.1f} s / {bench['meshopt_ms'] / 1000:.1f} s) |")
for name, x in (("with the error curve", c), ("`--no-error-curve`", n)):
    print(f"| conversion {name}: seconds (import, build, curve, write) | {x['seconds']:.1f} ({x['import']:.2f}, {x['build']:.1f}, {x['curve']:.1f}, {x['write']:.2f}) |")
    print(f"| conversion {name}: peak memory | {x['peak_bytes'] / 2**30:.2f} GiB, {x['peak_bytes'] / triangles:.0f} bytes per triangle |")
print(f"| import + write / build | {(c['import'] + c['write']) / c['build']:.1%} |")
print(f"| report of {report_triangles:,} triangles (`--report-json`): seconds, peak memory | {r['seconds']:.1f} s, {r['peak_bytes'] / 1e9:.2f} GB |")
if large:
    x = out["large_report"]
    print(f"| report of {triangles:,} triangles (`--large-report`): seconds, peak memory | {x['seconds']:.1f} s, {x['peak_bytes'] / 1e9:.2f} GB |")
print(f"| data/ ({inputs} inputs, -j 2): first run, unchanged rerun | {first:.2f} s, {rerun:.2f} s ({rerun / first:.1%}) |")
PY
