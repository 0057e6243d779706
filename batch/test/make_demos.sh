#!/bin/sh
# Makes the short demo sessions the batch pipeline tests read: DIR/seed1..seedN, 3 s each, not
# analysed. Each appears under its final name only when complete; existing ones are kept.
# usage: make_demos.sh DREAMSENSE DIR N
set -u
exe=$1 dir=$2 n=$3
mkdir -p "$dir" || exit 1
make_one() {
  [ -f "$dir/seed$1/session.yaml" ] && return 0
  rm -rf "$dir/seed$1.tmp"
  "$exe" -q demo --out "$dir/seed$1.tmp" --seed "$1" --duration 3 --no-analyze >/dev/null &&
    rm -rf "$dir/seed$1" && mv "$dir/seed$1.tmp" "$dir/seed$1"
}
# Two at a time (two cores).
pids=""
rc=0
s=1
while [ "$s" -le "$n" ]; do
  make_one "$s" &
  pids="$pids $!"
  if [ $((s % 2)) -eq 0 ]; then
    for p in $pids; do wait "$p" || rc=1; done
    pids=""
  fi
  s=$((s + 1))
done
for p in $pids; do wait "$p" || rc=1; done
exit $rc
