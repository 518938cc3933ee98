#!/usr/bin/env bash
# cmake --install puts headers, libraries, tools, a CMake package and a pkg-config file in a
# prefix. The consumers of samples/consumer build against it: with find_package (one on the
# runtime, one C program on tom::c, one linking every component) and with a plain C compiler
# and pkg-config; each extracts the same level as tomextract, index for index.
set -euo pipefail
src="$1"; build="$2"; data="$3"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
for f in include/tom/extract.h include/tom/format.h include/tom/builder/builder.h include/tom/builder/writer.h \
         include/tom/io/import.h include/tom/metrics/report.h include/tom/metrics/report_json.h include/tcr/model.h include/tcr/calibrate.h \
         include/tom/tom.h include/tom/tcr.h bin/tombuild bin/tominfo share/doc/tom/LICENSE share/doc/tom/CHANGELOG.md share/doc/tom/report.schema.json; do
  [ -e "$work/prefix/$f" ] || { echo "not installed: $f"; exit 1; }
done
# the private headers stay private, and the runtime's headers include nothing of the other libraries
if find "$work/prefix/include" -name parallel.h -o -name format_layout.h | grep -q .; then echo "an internal header was installed"; exit 1; fi
if grep -l '#include "tom/\(builder\|io\|metrics\)/' "$work/prefix"/include/tom/*.h; then echo "a runtime header includes another library's"; exit 1; fi
ls "$work/prefix"/lib*/cmake/tom/tomConfig.cmake >/dev/null
cmake -S "$src/samples/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/consumer" -j 2 >/dev/null
"$work/prefix/bin/tombuild" "$data/meshes/fandisk.off" -o "$work/out" -q
out="$("$work/consumer/tom_consumer" "$work/out/fandisk.tom")"
echo "$out"
echo "$out" | grep -q "fandisk: 6475 vertices, 12946 triangles; at 10%: .* vertices, 129[0-9] triangles, 38[0-9][0-9] indices"
[ "$("$work/consumer/tom_c_consumer" "$work/out/fandisk.tom")" = "$out" ] || { echo "the C consumer's counts differ"; exit 1; }

# a plain C compiler and pkg-config, nothing else
pc="$(ls -d "$work"/prefix/lib*/pkgconfig | head -1)"
PKG_CONFIG_PATH="$pc" cc -std=c99 -Wall -Wextra -pedantic -Werror "$src/samples/consumer/consumer.c" -o "$work/c_consumer" \
  $(PKG_CONFIG_PATH="$pc" pkg-config --cflags --libs tom)
[ "$("$work/c_consumer" "$work/out/fandisk.tom")" = "$out" ] || { echo "the pkg-config C consumer's counts differ"; exit 1; }

# Python from the installed package, nothing else on its path
site="$work/prefix/lib/python3/dist-packages"
[ -f "$site/tom/__init__.py" ] && ls "$site"/tom/_tom*.so >/dev/null || { echo "the Python package is not installed under $site"; exit 1; }
[ "$(PYTHONPATH="$site" /usr/bin/python3 "$src/samples/consumer/consumer.py" "$work/out/fandisk.tom")" = "$out" ] || { echo "the Python consumer's counts differ"; exit 1; }

# the same indices as tomextract at 10% and 1%, from each consumer
for fraction in 0.1 0.01; do
  "$work/prefix/bin/tomextract" "$work/out/fandisk.tom" --fraction "$fraction" -o "$work/level.obj" >/dev/null
  grep '^f ' "$work/level.obj" > "$work/level.faces"
  [ -s "$work/level.faces" ] || { echo "tomextract wrote no faces"; exit 1; }
  for consumer in "$work/consumer/tom_consumer" "$work/consumer/tom_c_consumer" "$work/c_consumer"; do
    "$consumer" "$work/out/fandisk.tom" "$fraction" | cmp -s - "$work/level.faces" || { echo "$(basename "$consumer") at $fraction: not tomextract's faces"; exit 1; }
  done
  PYTHONPATH="$site" /usr/bin/python3 "$src/samples/consumer/consumer.py" "$work/out/fandisk.tom" "$fraction" | cmp -s - "$work/level.faces" ||
    { echo "consumer.py at $fraction: not tomextract's faces"; exit 1; }
done

# every component: import, build, write, map, measure, select
pipeline="$("$work/consumer/tom_pipeline" "$data/meshes/fandisk.off" "$work/pipeline.tom")"
echo "$pipeline"
echo "$pipeline" | grep -Eq "^fandisk: 6475 vertices, 12946 triangles; at 10%: [0-9]+ vertices, 129[0-9] triangles, Hausdorff 0\.[0-9]+% of the diagonal; a 1 ms budget draws [0-9]+ \+ [0-9]+ triangles"
# a whole scene: one line per instance and part, as tominfo counts them, each range inside the level
"$work/prefix/bin/tombuild" "$data/assimp/glTF2/ClearCoat-glTF/ClearCoatTest.gltf" -o "$work/scene" -q
"$work/consumer/tom_scene" "$work/scene/ClearCoatTest.tom" > "$work/scene.txt"
"$work/prefix/bin/tominfo" "$work/scene/ClearCoatTest.tom" --json > "$work/scene.json"
/usr/bin/python3 -c "
import json, re
info = json.load(open('$work/scene.json'))
lines = open('$work/scene.txt').read().splitlines()
meshes = [i['mesh'] for i in info['instances']] or list(range(info['mesh_count']))
expected = sum(len(info['meshes'][m].get('parts', [0])) for m in meshes)
assert len(meshes) > 1 and len(lines) == expected, (len(lines), expected)
for line in lines:
    mesh, first, count = map(int, re.match(r'mesh (\d+) at .*indices \[(\d+), \+(\d+)\)', line).groups())
    assert first + count <= 3 * info['meshes'][mesh]['triangles'] and count % 3 == 0, line
print(f'tom_scene: {len(lines)} draws of {len(meshes)} instances')
"
# the time-critical loop on tom::tcr: the governor holds 10 ms under a renderer 1.3x slower than calibrated
governed="$("$work/consumer/tom_governed" "$work/out/fandisk.tom" 10)"
echo "$governed"
echo "$governed" | /usr/bin/python3 -c "
import re, sys
line = sys.stdin.read()
objects, frames, over, mean, triangles = re.match(r'(\d+) objects, (\d+) frames at 10.0 ms: (\d+) over 1.1x the budget, mean ([0-9.]+) ms, (\d+) triangles a frame', line).groups()
assert int(objects) == 64 and int(frames) > 200 and int(over) <= 0.05 * int(frames) and 7.5 < float(mean) < 10.5 and int(triangles) > 10000, line
"
# A governed loop's line: it calibrated a renderer it times, ran OBJECTS objects at BUDGET ms for
# at least MIN_FRAMES recorded frames, a few of them over 1.1x (real frames; the test runs alone),
# the mean within 0.7 to 1.05 of the budget, and drew part of the triangles, not all: the budget
# is below what full detail takes, so the governor must cut.
check_loop_line() {
  echo "$1" | /usr/bin/python3 -c "
import re, sys
objects, budget, min_frames = $2, $3, $4
line = sys.stdin.read()
per_tri, frames, over, mean, share = re.match(r'calibrated ([0-9.e+-]+) ms a triangle; %d objects, (\d+) frames at %.1f ms: (\d+) over 1.1x the budget, mean ([0-9.]+) ms, (\d+)%% of the triangles' % (objects, budget), line).groups()
assert float(per_tri) > 0 and int(frames) >= min_frames and int(over) <= 0.12 * int(frames), line
assert 0.7 * budget < float(mean) < 1.05 * budget and 5 < int(share) < 95, line
"
}
# Runs a governed loop (OBJECTS BUDGET MIN_FRAMES, then the command) and checks its line. The
# frames are timed on this shared 2-core machine: RUN_SERIAL keeps other tests away, not other
# processes, and a burst of outside load (seen once in CI, 35 of 170 frames over) can spoil one
# run. So a failed run is run once more, and that second run must pass; a governor that does not
# hold its budget fails both.
check_calibrated_loop() {
  local objects="$1" budget="$2" min_frames="$3" line
  shift 3
  line="$("$@")"
  echo "$line"
  check_loop_line "$line" "$objects" "$budget" "$min_frames" 2>/dev/null && return 0
  echo "install_test: that run missed its budget; running it once more"
  line="$("$@")"
  echo "$line"
  check_loop_line "$line" "$objects" "$budget" "$min_frames"
}
# the same loop from C, calibrated on the CPU renderer it times (clock(): this process's time)
check_calibrated_loop 64 2.0 151 "$work/consumer/tom_c_governed" "$work/out/fandisk.tom" 2
# and from Python, calibrated on a numpy renderer it times
check_calibrated_loop 16 3.0 100 env PYTHONPATH="$site" /usr/bin/python3 "$src/samples/consumer/governed.py" "$work/out/fandisk.tom" 3
echo "9 passed, 0 failed"
