#!/usr/bin/env bash
# The same progressive passes, rendered three ways on this machine's 2 cores, wall time from
# submit (or start) to the merged image:
#   slurm 1x2   a 1-task array with --cpus-per-task=2 (one process, 2 threads) + merge job
#   slurm 2x1   a 2-task array with --cpus-per-task=1 (two processes, 1 thread each) + merge job
#   direct      one `photon render --passes 0..N --threads 2` + `photon merge`, no Slurm
# on a throw-away cluster (.ci/slurm; as root). Each is repeated, in turns; prints every run (for
# Slurm runs also the longest task's own time), the median of each, and checks that every merged
# image is the same file, bit for bit. Run it on a quiet machine: under load, Linux's autogroup
# scheduler gives each Slurm job (its own session) a CPU share, which favours 2 tasks over 1.
#
#   benches/slurm-split.sh [--dry] [--repeat R] [--passes N] [-- photon render args]
#
# Defaults: 3 repeats, 8 passes, scenes/cornell-glass.pbrt with
# --res 256x256 --pass-spp 4 --global-photons 100000 --caustic-photons 100000 --seed 1.
# --dry uses tests/slurm-lib.sh's stub photon (measures only the Slurm overhead).
set -uo pipefail
cd "$(dirname "$0")/.." || exit 2
. tests/slurm-lib.sh

DRY=0 repeat=3 passes=8
args=(--res 256x256 --pass-spp 4 --global-photons 100000 --caustic-photons 100000 --seed 1)
while [ $# -gt 0 ]; do
  case "$1" in
    --dry) DRY=1; shift ;;
    --repeat) repeat=$2; shift 2 ;;
    --passes) passes=$2; shift 2 ;;
    --) shift; args=("$@"); break ;;
    *) echo "usage: benches/slurm-split.sh [--dry] [--repeat R] [--passes N] [-- render args]" >&2; exit 2 ;;
  esac
done
scene=scenes/cornell-glass.pbrt
work=$(mktemp -d /tmp/photon-slurm-bench.XXXXXX)

direct() { # DIR
  mkdir -p "$1"
  "$PHOTON_BIN" render "$scene" --progressive --passes "0..$passes" --threads 2 "${args[@]}" \
    -o "$1/part.exr" --no-png >"$1/render.log" 2>&1 &&
    "$PHOTON_BIN" merge "$1/part.exr" -o "$1/image.exr" --no-png >"$1/merge.log" 2>&1
}

# One timed run of configuration NAME into DIR; appends "NAME seconds" to $work/times.
run() { # NAME DIR
  local t0
  case "$1" in
    slurm-1x2) PHOTON_CPUS_PER_TASK=2 submit_and_wait 3600 "$scene" "$passes" 1 "$2" "${args[@]}" ;;
    slurm-2x1) PHOTON_CPUS_PER_TASK=1 submit_and_wait 3600 "$scene" "$passes" 2 "$2" "${args[@]}" ;;
    direct) t0=$(now); direct "$2"; RUN_SECONDS=$(since "$t0") ;;
  esac || { echo "$1 failed; logs in $2" >&2; exit 1; }
  echo "$1 $RUN_SECONDS" >>"$work/times"
  echo "$1 $RUN_SECONDS s$(longest_task "$2")"
}

# For a Slurm run: the longest task's own time (from its log), the rest being Slurm's overhead
# (scheduling, job start-up, the merge job).
longest_task() { # DIR
  local t
  t=$(cat "$1"/logs/render-*.log 2>/dev/null | sed -n 's/^task .* done in \([0-9.]*\) s$/\1/p' | sort -g | tail -n 1)
  [ -z "$t" ] || echo " (longest task ${t} s)"
}

photon_binary "$work" || exit 1
cluster_up || exit 1
echo "cluster up in $UP_SECONDS s; $passes passes, render args: ${args[*]}"
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg) ($(nproc) CPUs)"
configs=(slurm-1x2 slurm-2x1 direct)
for ((r = 0; r < repeat; r++)); do
  for c in "${configs[@]}"; do run "$c" "$work/$c-$r"; done
done
for c in "${configs[@]}"; do
  printf '%-10s median %s s over %d runs\n' "$c" \
    "$(awk -v c="$c" '$1 == c { print $2 }' "$work/times" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }')" "$repeat"
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
status=0
for f in "$work"/*/image.exr; do
  cmp -s "$f" "$work/direct-0/image.exr" || { echo "$f differs from direct-0/image.exr" >&2; status=1; }
done
[ "$status" = 0 ] && echo "all $(find "$work" -name image.exr | wc -l) merged images identical" && rm -rf "$work"
cluster_down || status=1
exit "$status"
