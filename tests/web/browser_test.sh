#!/usr/bin/env bash
# ctest browser_viewer: builds the browser runtime and viewer (scripts/build-web.sh, into the build
# folder), then streams .tom files into the viewer in headless chromium (browser_test.mjs).
#   browser_test.sh SOURCE_DIR BUILD_DIR DATA_DIR
set -euo pipefail
source_dir="$1" build_dir="$2" data_dir="$3"
TOM_WEB_BUILD="$build_dir/web" bash "$source_dir/scripts/build-web.sh"
node "$source_dir/tests/web/browser_test.mjs" --tools "$build_dir/tools" --tomview "$build_dir/samples/walkthrough/tomview" \
  --site "$build_dir/web/site" --data "$data_dir" --work "$build_dir/tests/web"
