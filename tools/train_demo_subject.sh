#!/usr/bin/env bash
# Re-fits the demo child's calibration shipped in data/subjects/demo_child (README "Subject
# calibration"): the 3-D face model (`train face`) and the gaze constants (`train gaze`), on demo
# seeds 101-104, which no evaluation uses (evaluations and tests use seeds < 100 or >= 200).
# Run it after changing the demo's face renderer or the face/gaze pipeline.
# Usage: bash tools/train_demo_subject.sh [WORK_DIR]   (needs build/bin/dreamsense)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bin=build/bin/dreamsense
work=${1:-$(mktemp -d)}
out=data/subjects/demo_child
seeds=(101 102 103 104)
mkdir -p "$work" "$out"
sessions=()
for s in "${seeds[@]}"; do
  [[ -f $work/T$s/session.yaml ]] || "$bin" -q demo --out "$work/T$s" --seed "$s" --child 0 --gestures classic --no-analyze
  sessions+=(--session "$work/T$s")
done
"$bin" train face "${sessions[@]}" --out "$out/face_model.yaml"
"$bin" train gaze "${sessions[@]}" --face-model "$out/face_model.yaml" --out "$out/gaze.yaml"
echo "demo child calibration written to $out (sessions in $work)"
