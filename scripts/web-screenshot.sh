#!/usr/bin/env bash
# The README's picture of the viewer mid-stream (docs/images/web-viewer.png): the 2CylinderEngine
# scene streamed to 15% of each mesh's triangles, taken by headless chromium from the site
# scripts/serve-web.sh serves.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
PORT=8137 bash scripts/serve-web.sh > /dev/null &
server=$!
trap 'kill $server 2>/dev/null; pkill -f "server.mjs --port 8137" || true' EXIT
until curl -sf -o /dev/null http://127.0.0.1:8137/; do sleep 0.5; done
profile="$(mktemp -d)"
chromium --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader --user-data-dir="$profile" --hide-scrollbars \
  --window-size=960,600 --virtual-time-budget=20000 --screenshot="$root/docs/images/web-viewer.png" \
  "http://127.0.0.1:8137/?file=models/2CylinderEngine.tom&resolution=0.15" 2>/dev/null
rm -rf "$profile"
echo "web-screenshot: docs/images/web-viewer.png"
