#!/usr/bin/env bash
# Enrolment (train speech) measured on FSDD by 5-fold cross-validation over takes, per speaker:
# adapt the TIDIGITS model on 40 takes per digit of one speaker, test the other 10 takes of the
# same speaker, against the packaged model on the same takes. Prints one line per fold and the
# mean per speaker (modalities/speech/README.md, "Enrolment").
#   bash tools/fsdd_enrolment_xval.sh [FSDD_DIR] [WORK_DIR]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
ds=$PWD/build/bin/dreamsense
fsdd=$(realpath "${1:-../shared/data/fsdd}")
work=${2:-$(mktemp -d /tmp/fsdd_enrolment.XXXXXX)}
mkdir -p "$work"
recordings=$fsdd; [[ -d $fsdd/recordings ]] && recordings=$fsdd/recordings
speakers=$(ls "$recordings" | sed -n 's/^[0-9]_\(.*\)_[0-9]*\.wav$/\1/p' | sort -u)
accuracy() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['metrics']['accuracy'])" "$1"; }
for s in $speakers; do
  for lo in 0 10 20 30 40; do
    hi=$((lo + 9)) f=$work/${s}_$lo
    rm -rf "$f" && mkdir -p "$f/enrol"
    for w in "$recordings"/*_"${s}"_*.wav; do  # the fold's enrolment takes, as links
      i=$(basename "$w" .wav); i=${i##*_}
      ((i < lo || i > hi)) && ln -s "$w" "$f/enrol/"
    done
    "$ds" -q train speech --dataset fsdd "$f/enrol" --out "$f/model"
    "$ds" -q eval speech --dataset fsdd "$fsdd" --speakers "$s" --indices $lo-$hi --no-items --json "$f/before.json"
    "$ds" -q eval speech --dataset fsdd "$fsdd" --speakers "$s" --indices $lo-$hi --no-items \
      --fsdd-model "$f/model" --json "$f/after.json"
    echo "$s takes $lo-$hi: $(accuracy "$f/before.json") -> $(accuracy "$f/after.json")"
  done
done | tee "$work/folds.txt"
awk '{n[$1]++; before[$1] += $4; after[$1] += $6}
     END {for (s in n) printf "%s mean: %.3f -> %.3f\n", s, before[s] / n[s], after[s] / n[s]}' "$work/folds.txt"
