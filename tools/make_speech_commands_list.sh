#!/usr/bin/env bash
# Writes the `train speech --dataset list` file of a Speech Commands folder: every clip of the ten
# command folders (word = folder) and of _unknown_ (word = the file-name prefix, e.g. dog_...),
# sorted; _silence_ and _background_noise_ are left out. Used for
# modalities/speech/models/speech_commands (MODEL_CARD.md).
# Usage: tools/make_speech_commands_list.sh DIR > list.txt
set -euo pipefail
dir=$(cd "$1" && pwd)
for word in yes no up down left right on off stop go; do
  find "$dir/$word" -maxdepth 1 -name '*.wav' | LC_ALL=C sort | sed "s|\$| $word|"
done
find "$dir/_unknown_" -maxdepth 1 -name '*.wav' | LC_ALL=C sort |
  while read -r f; do b=$(basename "$f"); echo "$f ${b%%_*}"; done
