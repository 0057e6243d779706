#!/usr/bin/env bash
# Re-creates data/demo/robot/prompt_*.wav, the demo robot's voice (sim/README.md), with Debian's
# espeak-ng (voice en-us, 150 words per minute, 22050 Hz mono 16-bit; the demo resamples to
# 16 kHz). espeak-ng 1.51+dfsg-10+deb12u2 gives byte-identical files.
set -euo pipefail
out="$(dirname "$0")/../data/demo/robot"
i=0
for text in "hello, shall we play a game" "ten of hearts" "go forward two meters" "well done" \
            "look at the car" "three of clubs"; do
  espeak-ng -v en-us -s 150 -w "$out/prompt_$i.wav" "$text"
  i=$((i + 1))
done
