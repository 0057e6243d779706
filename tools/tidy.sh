#!/usr/bin/env bash
# clang-tidy with the repository's .clang-tidy on C++ sources, using build/compile_commands.json.
#   bash tools/tidy.sh            the .cpp files this branch changes against main (CI)
#   bash tools/tidy.sh --all      every .cpp file of the build (slow: minutes per core)
#   bash tools/tidy.sh FILE...    these files
#   bash tools/tidy.sh --wide FILE...  the wide advisory set (tools/clang-tidy-wide.yaml) instead
# Skips (exit 0) when clang-tidy is not installed; exits 1 on any finding.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
tidy=$(command -v clang-tidy || true)
if [[ -z $tidy ]]; then
  echo "tidy: clang-tidy not installed, skipped"
  exit 0
fi
build=${DREAMSENSE_BUILD_DIR:-build}
if [[ ! -f $build/compile_commands.json ]]; then
  echo "tidy: $build/compile_commands.json missing (configure first)" >&2
  exit 1
fi
config=()
if [[ ${1:-} == --wide ]]; then
  config=(--config-file=tools/clang-tidy-wide.yaml)
  shift
fi
if [[ ${1:-} == --all ]]; then
  mapfile -t files < <(git ls-files '*.cpp')
elif [[ $# -gt 0 ]]; then
  files=("$@")
else
  base=$(git merge-base HEAD main 2>/dev/null || git rev-parse HEAD~1)
  [[ $base == "$(git rev-parse HEAD)" ]] && base=$(git rev-parse HEAD~1)
  mapfile -t files < <(git diff --name-only --diff-filter=AMR "$base" -- '*.cpp')
fi
# Only files the build compiles (tests and benches included when configured). The release preset
# is a unity build: tools/tidy/per_file_commands.py gives each source its unity file's command.
commands=$(mktemp -d)
trap 'rm -rf "$commands"' EXIT
mapfile -t checked < <(python3 tools/tidy/per_file_commands.py "$build" "$commands" "${files[@]}")
if [[ ${#checked[@]} -eq 0 ]]; then
  echo "tidy: no compiled .cpp files to check"
  exit 0
fi
echo "tidy: ${#checked[@]} files"
printf '%s\n' "${checked[@]}" | xargs -P "${TIDY_JOBS:-2}" -n 4 "$tidy" -p "$commands" --quiet "${config[@]}"
