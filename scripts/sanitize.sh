#!/usr/bin/env bash
# The libraries' test suite (every Catch2 test: the readers with their hostile files, the
# builder, extraction, the metrics and libtcr) built with AddressSanitizer and
# UndefinedBehaviorSanitizer in build-asan/; any report fails its test. The command-line and
# walkthrough scripts run in the plain build (scripts/test.sh): their time and memory limits do
# not hold under ASan. Installs what is missing and fetches the samples first.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
scripts/install-deps.sh
scripts/fetch-samples.sh
cmake -S "$root" -B "$root/build-asan" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTOM_SANITIZE=ON -DTOM_BUILD_SAMPLES=OFF -DTOM_BUILD_TOOLS=OFF >/dev/null
cmake --build "$root/build-asan" -j "$(nproc)"
export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$root/tests/fuzz/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export TOM_SANITIZED=1  # the CLI test skips the memory-limit checks ASan's address space rules out
ctest --test-dir "$root/build-asan" --output-on-failure -j "$(nproc)" -E "^(cli_contract|batch_contract|slurm_array|install_consumer|walkthrough)$" "$@"
