#!/usr/bin/env bash
# Serves the viewer with streamed samples: builds the browser runtime and viewer
# (scripts/build-web.sh), streams bunny00 and the 2CylinderEngine scene into
# build-web/site/models/ (tombuild --stream), and serves the site at http://127.0.0.1:8080/
# with samples/web/server.mjs (Range requests honoured).
#   PORT=8080 THROTTLE=BYTES_PER_SECOND (to watch the refinement) scripts/serve-web.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
bash scripts/build-web.sh
[ -x build/tools/tombuild ] || bash scripts/build.sh
[ -f data/meshes/bunny00.off ] || bash scripts/fetch-samples.sh
build/tools/tombuild data/meshes/bunny00.off data/assimp/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb --stream -o build-web/site/models -q
port="${PORT:-8080}"
echo "open http://127.0.0.1:$port/?file=models/bunny00.tom (or ?file=models/2CylinderEngine.tom, several file= at once)"
exec node samples/web/server.mjs --port "$port" ${THROTTLE:+--throttle "$THROTTLE"} build-web/site
