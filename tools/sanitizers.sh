#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer run (CI, after the README's test command; issue 18):
# configures the asan preset (clang, build-asan/), builds only what the labels unit, analyzer
# and fuzz need (target sanitizer_tests: those tests and the libFuzzer harnesses of fuzz/) and
# runs them. A sanitizer report fails the test that made it.
#   bash tools/sanitizers.sh                 unit|analyzer|fuzz (CI)
#   bash tools/sanitizers.sh -L fuzz         other ctest arguments instead of the label choice
# The asan test preset sets ASAN/LSAN/UBSAN_OPTIONS: reports in Debian's libraries (not our
# code) are suppressed in tools/sanitizers/*.supp, each entry with its reason.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
start=$SECONDS
cmake --preset asan "${launcher[@]}" >/dev/null
cmake --build --preset asan --target sanitizer_tests -j "$(nproc)"
echo "sanitizers: build $((SECONDS - start)) s" >&2
start=$SECONDS
if (($# == 0)); then set -- -L 'unit|analyzer|fuzz'; fi
status=0
ctest --preset asan "$@" || status=$?
echo "sanitizers: tests $((SECONDS - start)) s" >&2
exit $status
