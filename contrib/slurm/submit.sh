#!/usr/bin/env bash
# Submits a progressive photon render as a Slurm job array plus a dependent merge job.
#
#   contrib/slurm/submit.sh SCENE PASSES TASKS OUTDIR [extra photon render args]
#
# e.g.  PHOTON_BIN=$PWD/target/release/photon PHOTON_CPUS_PER_TASK=4 \
#         contrib/slurm/submit.sh scenes/cornell-glass.pbrt 64 16 /shared/run1 --pass-spp 4
#
# Task t of the array (render-array.sbatch) renders passes [t*PASSES/TASKS, (t+1)*PASSES/TASKS)
# into OUTDIR/parts/; the merge job (merge.sbatch) starts once every task has succeeded
# (--dependency=afterok:ARRAY) and writes OUTDIR/image.exr and image.png; if a task fails, the
# merge job is cancelled (--kill-on-invalid-dep=yes) instead of waiting forever. Job logs go to
# OUTDIR/logs/. Prints `array=JOBID`, `merge=JOBID` and `outdir=DIR`; wait for the merge with
# contrib/slurm/wait.sh JOBID, `squeue`, or `scontrol show job JOBID`.
#
# Environment:
#   PHOTON_BIN            photon binary (default: `photon` on PATH, then this checkout's
#                         target/release/photon). On a real cluster the binary, the scene (and
#                         its includes) and OUTDIR must be on a filesystem every node mounts at
#                         the same path (NFS, Lustre, ...); the paths are made absolute here.
#   PHOTON_CPUS_PER_TASK  CPUs (= render threads) per array task (default 1).
#   PHOTON_SBATCH_ARGS    extra sbatch options for both jobs, e.g. "--partition=gpu --time=2:00:00"
#                         (sbatch's own SBATCH_PARTITION, SBATCH_TIMELIMIT, ... work as well).
set -euo pipefail

usage="usage: submit.sh SCENE PASSES TASKS OUTDIR [extra photon render args]"
die() { echo "submit.sh: $*" >&2; exit 2; }
[ $# -ge 4 ] || die "$usage"
scene=$1 passes=$2 tasks=$3 outdir=$4
shift 4
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

[[ $passes =~ ^[1-9][0-9]*$ ]] || die "PASSES: '$passes' is not a positive integer"
[[ $tasks =~ ^[1-9][0-9]*$ ]] || die "TASKS: '$tasks' is not a positive integer"
[ "$tasks" -le "$passes" ] || die "TASKS: $tasks tasks for $passes passes would leave tasks without a pass"
[ -r "$scene" ] || die "SCENE: cannot read '$scene'"
cpus=${PHOTON_CPUS_PER_TASK:-1}
[[ $cpus =~ ^[1-9][0-9]*$ ]] || die "PHOTON_CPUS_PER_TASK: '$cpus' is not a positive integer"
bin=${PHOTON_BIN:-$(command -v photon || echo "$here/../../target/release/photon")}
[ -x "$bin" ] || die "PHOTON_BIN: '$bin' is not an executable (build with cargo build --release)"
bin=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")
scene=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")
mkdir -p "$outdir"
outdir=$(cd "$outdir" && pwd)
if compgen -G "$outdir/parts/part-*.exr" >/dev/null || [ -e "$outdir/image.exr" ]; then
  die "OUTDIR: $outdir already holds parts or an image; use a new directory"
fi
mkdir -p "$outdir/parts" "$outdir/logs"

read -r -a extra <<<"${PHOTON_SBATCH_ARGS:-}"
# The jobs get PHOTON_BIN and PHOTON_ARRAY_TASKS through the environment (--export=ALL), not
# in --export's comma-separated list, where a comma in the binary's path would start another
# variable (e.g. LD_PRELOAD).
export PHOTON_BIN=$bin PHOTON_ARRAY_TASKS=$tasks
common=(--parsable --export=ALL --chdir="$outdir" "${extra[@]}")
array=$(sbatch "${common[@]}" --array="0-$((tasks - 1))" --cpus-per-task="$cpus" \
  --output="$outdir/logs/render-%A_%a.log" \
  "$here/render-array.sbatch" "$scene" "$passes" "$outdir" "$@")
array=${array%%;*}
merge=$(sbatch "${common[@]}" --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --cpus-per-task=1 --output="$outdir/logs/merge-%j.log" \
  "$here/merge.sbatch" "$outdir" "$passes")
merge=${merge%%;*}
echo "array=$array"
echo "merge=$merge"
echo "outdir=$outdir"
