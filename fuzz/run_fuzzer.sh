#!/usr/bin/env bash
# Runs one libFuzzer harness for a fixed time on a fresh copy of its seed corpus (ctest label
# fuzz; fuzz/README.md). A crash, leak, sanitizer report or timeout fails the test; the input
# that caused it is kept as WORK/artifacts/crash-* (reproduce: FUZZER WORK/artifacts/crash-...).
#   run_fuzzer.sh FUZZER SEED_DIR WORK SECONDS [SELECTOR:FILE ...]
# SELECTOR:FILE seeds a repository file prefixed with the selector byte the harness reads first.
set -euo pipefail
fuzzer=$1 seed_dir=$2 work=$3 seconds=$4
shift 4
rm -rf "$work/corpus"
mkdir -p "$work/corpus" "$work/artifacts"
if [[ -d $seed_dir ]]; then cp "$seed_dir"/* "$work/corpus/"; fi
n=0
for s in "$@"; do
  selector=${s%%:*} file=${s#*:}
  {
    printf "\\x$(printf %02x "$selector")"
    cat "$file"
  } >"$work/corpus/repo-seed-$n"
  n=$((n + 1))
done
# -timeout: one input taking longer is a finding (a hang); 30 s because ASan needs up to 10 s to
# map and release the 17 GB of a huge declared matrix (below) on a loaded 2-core machine
# (fuzz.calibration timed out at 10 s so, 2026-11-25); -rss_limit_mb: so is memory really used. No limit on one allocation (-malloc_limit_mb): OpenCV allocates a matrix's declared size
# before it checks the data against it, so a file declaring 2^31 rows asks for 17 GB of address
# space that is never touched and is released with a clean error (fuzz/README.md, findings).
# Inputs grow up to the largest seed (at least 4 kB, libFuzzer's default).
export ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}allocator_may_return_null=1
exec "$fuzzer" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=2560 \
  -malloc_limit_mb=1000000000 \
  -print_final_stats=1 -artifact_prefix="$work/artifacts/" "$work/corpus"
