#!/usr/bin/env bash
# cmake --install puts headers, libraries, tools and a CMake package in a prefix, and the
# minimal consumer in samples/consumer builds against it with find_package and runs.
set -euo pipefail
src="$1"; build="$2"; data="$3"
work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
for f in include/tom/extract.h include/tom/format.h include/tom/builder/builder.h include/tom/builder/writer.h \
         include/tom/io/import.h include/tom/metrics/report.h include/tcr/model.h bin/tombuild bin/tominfo; do
  [ -e "$work/prefix/$f" ] || { echo "not installed: $f"; exit 1; }
done
# the private headers stay private, and the runtime's headers include nothing of the other libraries
if find "$work/prefix/include" -name parallel.h -o -name format_layout.h | grep -q .; then echo "an internal header was installed"; exit 1; fi
if grep -l '#include "tom/\(builder\|io\|metrics\)/' "$work/prefix"/include/tom/*.h; then echo "a runtime header includes another library's"; exit 1; fi
ls "$work/prefix"/lib*/cmake/tom/tomConfig.cmake >/dev/null
cmake -S "$src/samples/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/consumer" >/dev/null
"$work/prefix/bin/tombuild" "$data/meshes/fandisk.off" -o "$work/out" -q
out="$("$work/consumer/tom_consumer" "$work/out/fandisk.tom")"
echo "$out"
echo "$out" | grep -q "fandisk: 6475 vertices, 12946 triangles; at 10%: .* vertices, 129[0-9] triangles, 38[0-9][0-9] indices"
echo "1 passed, 0 failed"
