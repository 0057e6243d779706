#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer run (CI, after the README's test command; issue 18):
# configures the asan preset (clang, build-asan/), builds only what the labels unit, analyzer
# and fuzz need (target sanitizer_tests: those tests and the libFuzzer harnesses of fuzz/) and
# runs them. A sanitizer report fails the test that made it.
#   bash tools/sanitizers.sh                 unit|analyzer|fuzz (what CI runs)
#   bash tools/sanitizers.sh -L fuzz         other ctest arguments instead of the label choice
# The asan test preset sets ASAN/LSAN/UBSAN_OPTIONS: reports in Debian's libraries (not our
# code) are suppressed in tools/sanitizers/*.supp, each entry with its reason.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
# Skipped (exit 0, one line on stderr) where clang or its ASan/UBSan/libFuzzer runtimes are missing
# (tools/setup.sh installs clang and libclang-rt-14-dev): a check that cannot run is said so.
probe_dir=$(mktemp -d)
trap 'rm -rf "$probe_dir"' EXIT
if ! command -v clang++ >/dev/null 2>&1; then
  echo "sanitizers: skipped (no clang++; tools/setup.sh installs it)" >&2
  exit 0
fi
printf 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }\n' \
  >"$probe_dir/probe.cpp"
if ! clang++ -fsanitize=address,undefined,fuzzer "$probe_dir/probe.cpp" -o "$probe_dir/probe" \
  >"$probe_dir/log" 2>&1; then
  echo "sanitizers: skipped (clang++ cannot link ASan/UBSan/libFuzzer: $(head -n 1 "$probe_dir/log");" \
    "install libclang-rt-14-dev)" >&2
  exit 0
fi
# Everything the labels unit, analyzer and fuzz run (target sanitizer_tests). CI runs this too
# (.ci/run); the asan preset is a unity build (CMakePresets.json), which keeps the cold build of
# these ~330 sources inside CI's time budget (docs/reliability.md, "In CI").
targets=(sanitizer_tests)
start=$SECONDS
cmake --preset asan >/dev/null
cmake --build --preset asan --target "${targets[@]}" -j "$(nproc)"
echo "sanitizers: build $((SECONDS - start)) s" >&2
start=$SECONDS
# Not under ASan, four measurements that run code other tests already run under ASan, on more
# data (their release runs stay in the README's test command):
# - FaceDetectionDemo.TwentySecondSession (240 s here): recall over 20 s of demo; the detector
#   runs under ASan in the FaceDetector, HogFaceDetector and FaceDetectionAnalyzer tests;
# - DemoSessionTest.SameSeedGivesByteIdenticalFiles (93 s): the simulator's determinism (three
#   sessions made); the other DemoSessionTest tests make sessions under ASan;
# - HeadPoseDemo.GenericModelVsPlanarModel (52 s) and FaceLandmarksDemo.EyeLandmarksNearTruthEyes
#   (51 s): accuracy over the demo; HeadPoseDemo.AnalyzerOverTheDemo runs the same demo run
#   (face detection, landmarks, head pose) under ASan.
not_under_asan='^(FaceDetectionDemo\.TwentySecondSession|DemoSessionTest\.SameSeedGivesByteIdenticalFiles'
not_under_asan+='|HeadPoseDemo\.GenericModelVsPlanarModel|FaceLandmarksDemo\.EyeLandmarksNearTruthEyes)$'
if (($# == 0)); then set -- -L 'unit|analyzer|fuzz' -E "$not_under_asan"; fi
status=0
ctest --preset asan "$@" || status=$?
echo "sanitizers: tests $((SECONDS - start)) s" >&2
exit $status
