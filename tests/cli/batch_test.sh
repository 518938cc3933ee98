#!/usr/bin/env bash
# tombuild at scale, on one machine: incremental reruns (up to date, changed input, changed
# .mtl or .bin, changed options, --force), outputs whose input is gone (named, --prune), the
# manifest, shards (--shard K/N and auto from Slurm's and Kubernetes' variables) whose merge
# gives the one-run bytes, manifest and summary, and a merge that names missing shards.
set -u
tools="$1"; data="$2"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
. "$(dirname "$0")/check.sh"
status_of() { grep "\"input\":\"[^\"]*$2\"" "$1" | sed 's/.*"status":"\([^"]*\)".*/\1/'; }
count_status() { grep -c "\"status\":\"$2\"" "$1"; }

[ -s "$data/meshes/fandisk.off" ] || { echo "samples missing: run scripts/fetch-samples.sh"; exit 1; }
mkdir -p "$work/in/obj" "$work/in/gltf"
cp "$data/meshes/fandisk.off" "$data/meshes/cow.off" "$data/meshes/mushroom.off" "$data/meshes/eight.off" "$work/in/"
cp "$data/assimp/OBJ/spider.obj" "$data/assimp/OBJ/spider.mtl" "$work/in/obj/"
cp "$data/assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf" "$data/assimp/glTF2/BoxTextured-glTF/BoxTextured0.bin" "$work/in/gltf/"
n=6
tb() { "$tools/tombuild" "$work/in" -o "$work/out" --report-json "$work/rep" "$@"; }

# a first run converts everything and says so in the manifest
check "first run" expect_exit 0 tb
m="$work/out/manifest.jsonl"
check "the manifest has a record per input, all converted" test "$(wc -l < "$m")" -eq $n -a "$(count_status "$m" converted)" -eq $n
check "records are in input order, with digest, output, triangles and seconds" /usr/bin/python3 - "$m" <<'PY'
import json, sys
rs = [json.loads(l) for l in open(sys.argv[1])]
assert [r["index"] for r in rs] == list(range(len(rs))), rs
assert [r["input"] for r in rs] == sorted(r["input"] for r in rs)
for r in rs:
    assert r["digest"].startswith("xxh3-128:") and len(r["digest"]) == 9 + 32, r
    assert r["output"].endswith(".tom") and r["triangles"] > 0 and r["seconds"] >= 0 and r["report"].endswith(".json"), r
PY
check "tominfo shows the provenance" bash -c "'$tools/tominfo' --json '$work/out/obj/spider.tom' | grep -q 'spider.mtl'"
cp "$work/rep/summary.csv" "$work/summary-first.csv"
cp -r "$work/out" "$work/out-first"

# an unchanged rerun converts nothing, rewrites nothing and keeps the summary
check "unchanged rerun" expect_exit 0 tb
check "every input is up to date" test "$(count_status "$m" "up to date")" -eq $n
check "the rerun says so" grep -q "0 of $n inputs converted, $n up to date" "$work/stdout"
check "the outputs are untouched" bash -c "for f in \$(cd '$work/out-first' && find . -name '*.tom'); do test '$work/out/'\$f -ot '$work/stdout' -a ! '$work/out/'\$f -nt '$work/out-first/'\$f || exit 1; cmp -s '$work/out-first/'\$f '$work/out/'\$f || exit 1; done"
check "the summary is rebuilt from the reports, row for row" diff "$work/summary-first.csv" "$work/rep/summary.csv"

# a changed input, .mtl or .bin converts that input alone
echo "# edited" >> "$work/in/cow.off"
echo "# edited" >> "$work/in/obj/spider.mtl"
printf '\001' | dd of="$work/in/gltf/BoxTextured0.bin" bs=1 seek=576 conv=notrunc status=none  # a texture coordinate's lowest byte
check "rerun after edits" expect_exit 0 tb
check "the edited OFF is converted" test "$(status_of "$m" cow.off)" = converted
check "the OBJ whose .mtl changed is converted" test "$(status_of "$m" spider.obj)" = converted
check "the glTF whose .bin changed is converted" test "$(status_of "$m" BoxTextured.gltf)" = converted
check "the others are up to date" test "$(count_status "$m" "up to date")" -eq 3
# a missing .mtl that appears later counts as a change
mv "$work/in/obj/spider.mtl" "$work/spider.mtl"
check "rerun without the .mtl" expect_exit 0 tb
check "the OBJ is converted when its .mtl goes" test "$(status_of "$m" spider.obj)" = converted
check "rerun still without it: up to date" expect_exit 0 tb
check "a missing .mtl that stays missing keeps it up to date" test "$(status_of "$m" spider.obj)" = "up to date"
mv "$work/spider.mtl" "$work/in/obj/spider.mtl"
check "rerun with the .mtl back" expect_exit 0 tb
check "the OBJ is converted when its .mtl comes back" test "$(status_of "$m" spider.obj)" = converted

# options that change the output convert everything; thread and job counts do not
check "rerun with -j 2 --build-threads 1" expect_exit 0 tb -j 2 --build-threads 1
check "the job and thread counts change nothing" test "$(count_status "$m" "up to date")" -eq $n
check "rerun with another pass fraction" expect_exit 0 tb --pass-fraction 0.2
check "a build option converts every input" test "$(count_status "$m" converted)" -eq $n
check "rerun with other report levels" expect_exit 0 tb --pass-fraction 0.2 --levels 50,10
check "a report option converts every input" test "$(count_status "$m" converted)" -eq $n
check "the summary has the new levels" bash -c "head -1 '$work/rep/summary.csv' | grep -q 'mean_10$'"
check "a missing report converts its input again" bash -c "rm '$work/rep/cow.json' && '$tools/tombuild' '$work/in' -o '$work/out' --report-json '$work/rep' --pass-fraction 0.2 --levels 50,10 -q && grep cow.off '$m' | grep -q '\"converted\"'"
check "rerun with --force" expect_exit 0 tb --pass-fraction 0.2 --levels 50,10 --force
check "--force converts every input" test "$(count_status "$m" converted)" -eq $n
check "a damaged output is converted again" bash -c "printf 'x' >> '$work/out/fandisk.tom' && '$tools/tombuild' '$work/in' -o '$work/out' -q && grep fandisk.off '$m' | grep -q '\"converted\"' && '$tools/tominfo' '$work/out/fandisk.tom' >/dev/null"

# --progress with one job shows each input's stages, and -v their seconds
check "--progress shows the stages of one input" bash -c "'$tools/tombuild' '$work/in/fandisk.off' -o '$work/prog' --progress -v 2>'$work/prog.err' >'$work/prog.out' && tr '\\r' '\\n' < '$work/prog.err' | grep -q 'fandisk.off: build ' && tr '\\r' '\\n' < '$work/prog.err' | grep -q 'fandisk.off: error curve 100%' && tr '\\r' '\\n' < '$work/prog.err' | grep -q 'fandisk.off: write'"
check "-v gives the seconds of each stage" grep -q "seconds: import [0-9.]*, build [0-9.]*, error curve and report [0-9.]*, write [0-9.]*" "$work/prog.out"

# an output whose input is gone is named, and removed only with --prune
rm "$work/in/eight.off"
check "rerun without eight.off" expect_exit 0 tb
check "the orphan is named" grep -q "eight.tom: no input of this run maps to it" "$work/stdout"
check "and kept" test -s "$work/out/eight.tom"
echo "not ours" > "$work/out/notes.tom"
check "rerun with --prune" expect_exit 0 tb --prune
check "--prune removes the orphan and its report" test ! -e "$work/out/eight.tom" -a ! -e "$work/rep/eight.json"
check "--prune leaves files tombuild did not make" test -s "$work/out/notes.tom"
check "the manifest lists the inputs left" test "$(wc -l < "$m")" -eq $((n - 1))
cp "$data/meshes/eight.off" "$work/in/"

# shards: a deterministic split balanced by size, whose merge is the one-run result
one="$work/one"; "$tools/tombuild" "$work/in" -o "$one" --report-json "$one-rep" -q || exit 1
for k in 0 1 2; do
  check "shard $k/3" expect_exit 0 "$tools/tombuild" "$work/in" -o "$work/sh" --report-json "$work/sh-rep" --shard $k/3 -q
done
check "each shard wrote its manifest part" test "$(ls "$work"/sh/manifest.shard-*-of-3.jsonl | wc -l)" -eq 3
check "the shards split the inputs" test "$(cat "$work"/sh/manifest.shard-*.jsonl | grep -c '"status"')" -eq $n
check "the largest input has a shard to itself" bash -c "grep -l fandisk '$work'/sh/manifest.shard-*.jsonl | xargs grep -c '\"status\"' | grep -qx 1"
check "the merge" expect_exit 0 "$tools/tombuild" --merge "$work/sh"
check "the merge reports what it joined" grep -q "merged 3 of 3 shards" "$work/stdout"
strip() { sed -e 's/,"seconds":[^}]*}/}/' -e "s#$2#DIR#g" "$1"; }
check "the merged manifest is the one-run manifest (but for the seconds)" \
  diff <(strip "$one/manifest.jsonl" "$one") <(strip "$work/sh/manifest.jsonl" "$work/sh")
check "the merged summary is the one-run summary (but for the timings)" \
  diff <(cut -d, -f1-4,7- "$one-rep/summary.csv") <(cut -d, -f1-4,7- "$work/sh-rep/summary.csv")
check "the shards' outputs are byte-identical to the one run's" bash -c "cd '$one' && for f in \$(find . -name '*.tom'); do cmp -s \$f '$work/sh/'\$f || exit 1; done"
# the README's GNU parallel recipe gives the same
check "GNU parallel runs 4 shards and the merge" bash -c "parallel --will-cite '$tools/tombuild' '$work/in' -o '$work/gp' --shard {}/4 -q ::: 0 1 2 3 && '$tools/tombuild' --merge '$work/gp' -q"
check "their outputs are the one run's" bash -c "cd '$one' && for f in \$(find . -name '*.tom'); do cmp -s \$f '$work/gp/'\$f || exit 1; done"
check "shard 1/3 again is up to date" bash -c "'$tools/tombuild' '$work/in' -o '$work/sh' --report-json '$work/sh-rep' --shard 1/3 | grep -q ' up to date'"
check "Slurm's variables choose the shard" bash -c "SLURM_ARRAY_TASK_ID=5 SLURM_ARRAY_TASK_MIN=4 SLURM_ARRAY_TASK_COUNT=3 '$tools/tombuild' '$work/in' -o '$work/sh' --shard auto | grep -q 'shard 1/3'"
check "Kubernetes' index chooses the shard" bash -c "JOB_COMPLETION_INDEX=2 '$tools/tombuild' '$work/in' -o '$work/sh' --shard auto/3 | grep -q 'shard 2/3'"
check "auto without a scheduler is a usage error" expect_exit 2 env -u SLURM_ARRAY_TASK_ID -u JOB_COMPLETION_INDEX "$tools/tombuild" "$work/in" -o "$work/sh" --shard auto
check "and says what is missing" grep -q "SLURM_ARRAY_TASK_ID" "$work/stderr"
check "--shard 3/3 is a usage error" expect_exit 2 "$tools/tombuild" "$work/in" -o "$work/sh" --shard 3/3
check "a Slurm array with a step is refused" expect_exit 2 env SLURM_ARRAY_TASK_ID=6 SLURM_ARRAY_TASK_MIN=0 SLURM_ARRAY_TASK_COUNT=4 "$tools/tombuild" "$work/in" -o "$work/sh" --shard auto
rm "$work/sh/manifest.shard-2-of-3.jsonl"
check "a merge with a shard missing fails" expect_exit 1 "$tools/tombuild" --merge "$work/sh"
check "and names the shard" grep -q "shard 2/3 is missing" "$work/stderr"
check "a merge of nothing fails" expect_exit 1 "$tools/tombuild" --merge "$work/in"
# a failing input makes its shard a failed one
printf 'OFF\n3 1 0\n0 0 0\n' > "$work/in/broken.off"
for k in 0 1; do "$tools/tombuild" "$work/in" -o "$work/sf" --shard $k/2 -q 2>/dev/null; done
check "a merge over a failed input fails" expect_exit 1 "$tools/tombuild" --merge "$work/sf"
check "and names the shard and the input" grep -q "shard [01]/2: 1 of [0-9]* inputs failed, first .*broken.off" "$work/stderr"
check "the failed record says why" bash -c "grep broken.off '$work/sf/manifest.jsonl' | grep -q '\"status\":\"failed\",\"message\":\"[^\"]*broken.off'"

echo "batch_test: $passed checks passed, $fail failed"
[ "$fail" -eq 0 ]
