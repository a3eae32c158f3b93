#!/bin/bash
# CPU time of the same render with several photon binaries, interleaved (A B C, A B C, ...):
# on a loaded machine user CPU time is much steadier than wall time. One thread, so that the
# render's CPU time is its own work.
#
#   benches/cpu-time.sh SCENE REPEATS "RENDER ARGS" NAME=BINARY...
#
# Prints one line per run: name, repeat, rays cast, user+system seconds, wall seconds,
# Mrays per CPU-second, and the load average before the run.
set -u
scene=$1; reps=$2; args=$3; shift 3
nice="nice -n -10"
$nice true 2>/dev/null || nice=""
tmp=$(mktemp -d)
for r in $(seq 1 "$reps"); do
  for pair in "$@"; do
    name=${pair%%=*}; bin=${pair#*=}
    load=$(cut -d' ' -f1 /proc/loadavg)
    # shellcheck disable=SC2086
    /usr/bin/time -f "%U %S %e" -o "$tmp/time" $nice "$bin" render "$scene" $args --threads 1 \
      -o "$tmp/out.exr" --no-png > "$tmp/log" 2>&1
    rays=$(sed -n 's/^rendered in [0-9.]* s: \([0-9]*\) rays.*/\1/p' "$tmp/log")
    read -r u s e < "$tmp/time"
    echo "$name $r rays $rays cpu $(echo "$u + $s" | bc) wall $e Mrays/cpu-s $(echo "scale=3; $rays / ($u + $s) / 1000000" | bc) load $load"
  done
done
rm -rf "$tmp"
