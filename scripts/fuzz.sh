#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, AddressSanitizer, UBSan) in build-fuzz/ and runs one, or
# all (as many side by side as there are cores), each for as long as asked, from its seed corpus
# (tests/fuzz/corpus/TARGET, plus seeds made from the sample meshes when data/ holds them) with
# its format's dictionary.
# Usage: scripts/fuzz.sh TARGET|all SECONDS [libFuzzer options...]
#        scripts/fuzz.sh list
# A finding ends the run with a non-zero exit and leaves the input in build-fuzz/findings/.
# TOM_FUZZ_BUILD=DIR builds and fuzzes in DIR instead (two runs at once need two folders).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
targets=(reader_fuzz stream_fuzz export_fuzz import_off_fuzz import_obj_fuzz import_ply_fuzz import_stl_fuzz import_gltf_fuzz import_glb_fuzz
         builder_fuzz calibration_fuzz scene_fuzz capi_fuzz)
if [ "${1:-}" = "list" ]; then printf '%s\n' "${targets[@]}"; exit 0; fi
[ $# -ge 2 ] || { echo "usage: scripts/fuzz.sh TARGET|all SECONDS [libFuzzer options...]" >&2; exit 2; }
target="$1"; seconds="$2"; shift 2
build="${TOM_FUZZ_BUILD:-$root/build-fuzz}"

CC=clang CXX=clang++ cmake -S "$root" -B "$build" -DTOM_FUZZ=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" -j "$(nproc)" >/dev/null

dict_of() {
  case "$1" in
    reader_fuzz|stream_fuzz|export_fuzz|capi_fuzz) echo tom ;;
    import_off_fuzz|builder_fuzz) echo off ;;
    import_obj_fuzz) echo obj ;;
    import_ply_fuzz) echo ply ;;
    import_stl_fuzz) echo stl ;;
    import_gltf_fuzz|import_glb_fuzz) echo gltf ;;
    calibration_fuzz) echo calibration ;;
    scene_fuzz) echo scene ;;
  esac
}

# the seeds: the committed ones, and what the samples and tools make (a .tom with coarse corners
# and 32-bit indices, a Draco glTF with its buffer embedded, meshopt-compressed glTF)
seed() {
  local t="$1" corpus="$build/corpus/$1"
  mkdir -p "$corpus"
  cp -n "$root/tests/fuzz/corpus/$t/"* "$corpus/" 2>/dev/null || true
  local tools="$root/build/tools" data="$root/data"
  case "$t" in
    reader_fuzz|export_fuzz|capi_fuzz)
      if [ -x "$tools/tombuild" ] && [ ! -f "$corpus/grid64-32bit.tom" ]; then
        /usr/bin/python3 -c "
n = 64
print('OFF'); print(n * n, 2 * (n - 1) * (n - 1), 0)
for j in range(n):
    for i in range(n): print(i, j, (i * 7 + j * 3) % 5 * 0.1)
for j in range(n - 1):
    for i in range(n - 1):
        a = j * n + i; print(3, a, a + 1, a + n + 1); print(3, a, a + n + 1, a + n)" > "$build/grid64-32bit.off"
        "$tools/tombuild" "$build/grid64-32bit.off" -o "$corpus" -q --index-size 32
      fi ;;
    import_gltf_fuzz)
      if [ -f "$data/assimp/glTF2/draco/2CylinderEngine.gltf" ] && [ ! -f "$corpus/draco-embedded.gltf" ]; then
        /usr/bin/python3 -c "
import base64, json, sys
d = json.load(open(sys.argv[1]))
d['buffers'][0]['uri'] = 'data:application/octet-stream;base64,' + base64.b64encode(open(sys.argv[2], 'rb').read()).decode()
json.dump(d, open(sys.argv[3], 'w'))" "$data/assimp/glTF2/draco/2CylinderEngine.gltf" "$data/assimp/glTF2/draco/2CylinderEngine.bin" "$corpus/draco-embedded.gltf"
      fi ;;
    stream_fuzz)  # streams with parts, texture coordinates and groups of copies
      if [ -x "$tools/tombuild" ] && [ -f "$data/assimp/OBJ/spider.obj" ] && [ ! -f "$corpus/spider.tom" ]; then
        "$tools/tombuild" "$data/assimp/OBJ/spider.obj" -o "$corpus" -q --stream --no-error-curve
        "$tools/tombuild" "$data/assimp/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb" -o "$corpus" -q --stream
      fi ;;
    import_glb_fuzz)
      local pack="$root/.tools/node_modules/gltfpack/cli.js"  # 0.18, whose output Debian's decoders read
      if [ -f "$pack" ] && [ ! -f "$corpus/cube-meshopt.glb" ]; then
        node "$pack" -i "$root/tests/fuzz/corpus/import_glb_fuzz/cube-lods.glb" -o "$corpus/cube-meshopt.glb" -c >/dev/null 2>&1 || true
        node "$pack" -i "$root/tests/fuzz/corpus/import_glb_fuzz/tetra.glb" -o "$corpus/tetra-quantized.glb" >/dev/null 2>&1 || true
      fi ;;
  esac
}

# one target's run, from its seeded corpus; its summary goes to $build/findings/TARGET.summary
# (printed by the caller, in target order, so that runs side by side do not interleave their lines)
run() {
  local t="$1"; shift
  mkdir -p "$build/findings/$t"
  local status=0
  { echo "fuzz: $t for $seconds s"; run_target "$t" "$@" || status=$?; } > "$build/findings/$t.summary" 2>&1
  return $status
}
run_target() {
  local t="$1"; shift
  # -malloc_limit_mb: an allocation of more than this from an input of a few KB is a finding
  "$build/tests/fuzz/$t" "$build/corpus/$t" -dict="$root/tests/fuzz/dict/$(dict_of "$t").dict" -max_total_time="$seconds" \
    -rss_limit_mb=2048 -malloc_limit_mb=512 -timeout=20 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$build/findings/$t/" "$@" > "$build/findings/$t.log" 2>&1
  local status=$?
  grep -E '^(#[0-9]+.*DONE|Done [0-9]+ runs|stat::number_of_executed_units|stat::peak_rss_mb|==[0-9]+==ERROR|SUMMARY|artifact_prefix|Test unit written)' "$build/findings/$t.log" || true
  [ $status -eq 0 ] || echo "fuzz: $t found something (exit $status): $build/findings/$t.log"
  return $status
}

export LSAN_OPTIONS="suppressions=$root/tests/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
status=0
# each libFuzzer run takes one core: "all" runs as many side by side as the machine has cores,
# each for the full time asked
if [ "$target" = all ]; then chosen=("${targets[@]}"); else chosen=("$target"); fi
for t in "${chosen[@]}"; do seed "$t"; done  # one after another: two targets make the same seed file
width=$(nproc)
for ((first = 0; first < ${#chosen[@]}; first += width)); do
  group=("${chosen[@]:first:width}")
  pids=()
  for t in "${group[@]}"; do run "$t" "$@" & pids+=($!); done
  for k in "${!group[@]}"; do
    wait "${pids[$k]}" || status=1
    cat "$build/findings/${group[$k]}.summary"
  done
done
exit $status
