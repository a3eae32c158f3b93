#!/usr/bin/env bash
# End-to-end test of contrib/slurm/ on a throw-away one-host Slurm cluster (.ci/slurm; as root,
# Debian 12; called by .ci/run after cargo test).
#
#   tests/slurm.sh [--dry] [--keep DIR]
#
# Brings the cluster up (and always down again, leaving no process behind), renders 8
# progressive passes of scenes/cornell-glass.pbrt at 64x64 as a 4-task array and as an uneven
# 3-task array (2+3+3 passes) with contrib/slurm/submit.sh, renders the same 8 passes in one
# process and merges that single part, and checks with cmp that all three merged EXRs are
# identical bit for bit. Also checks that a failing array cancels its merge job instead of
# leaving it waiting, that one task submitted again alone writes the same part, that
# merge.sbatch refuses parts with a pass range missing and that submit.sh refuses an output
# directory that already holds parts. Before the cluster comes up, hostile names: a part name
# carrying `$(cmd)` is refused without running cmd, an OUTDIR with a space and `*` reaches
# photon as one word, and a comma in PHOTON_BIN's path never reaches sbatch's --export list
# (a fake sbatch records what it was given). Prints timings and ends with "N passed, M failed"; exit
# status 1 on any failure.
# --dry replaces photon by a shell stub (tests/slurm-lib.sh: stub_photon) whose "parts" are
# text files: it tests the cluster plumbing without the renderer's progressive mode.
# --keep DIR keeps the job directories (parts, logs, images) in DIR instead of a temporary one.
set -uo pipefail
cd "$(dirname "$0")/.." || exit 2
. tests/slurm-lib.sh

DRY=0 work=""
while [ $# -gt 0 ]; do
  case "$1" in
    --dry) DRY=1; shift ;;
    --keep) work=$2; shift 2 ;;
    *) echo "usage: tests/slurm.sh [--dry] [--keep DIR]" >&2; exit 2 ;;
  esac
done
if [ -z "$work" ]; then
  work=$(mktemp -d /tmp/photon-slurm-test.XXXXXX)
  cleanup_work=1
else
  mkdir -p "$work"; work=$(cd "$work" && pwd); cleanup_work=0
fi

passed=0 failed=0
check() { # NAME COMMAND...: runs COMMAND, counts and prints the result, returns its status
  local name=$1; shift
  if "$@"; then passed=$((passed + 1)); echo "ok   $name"
  else failed=$((failed + 1)); echo "FAIL $name"; return 1; fi
}
summary() {
  echo "$passed passed, $failed failed"
  if [ "$cleanup_work" = 1 ] && [ "$failed" = 0 ]; then rm -rf "$work"; else echo "job directories kept in $work"; fi
  [ "$failed" = 0 ]
}

scene=scenes/cornell-glass.pbrt
args=(--res 64x64 --pass-spp 4 --global-photons 5000 --caustic-photons 5000 --seed 7)
timeout=300

# Prints a job directory's logs (on failure).
show_logs() { tail -n 8 "$1"/logs/*.log 2>/dev/null | sed 's/^/    /' >&2; }

array_run() { # NAME TASKS: renders the 8 passes as a TASKS-task array into $work/NAME
  if submit_and_wait "$timeout" "$scene" 8 "$2" "$work/$1" "${args[@]}"; then
    echo "     $2-task array + merge: ${RUN_SECONDS} s from submit to merged image (jobs $ARRAY_JOB, $MERGE_JOB)"
  else
    show_logs "$work/$1"; return 1
  fi
}
parts_are() { # NAME COUNT
  local n
  n=$(find "$work/$1/parts" -name 'part-*.exr' | wc -l)
  [ "$n" = "$2" ] || { echo "     $1: $n parts, expected $2" >&2; return 1; }
}

single_run() { # renders the 8 passes in one process and merges the single part
  local t0
  t0=$(now)
  mkdir -p "$work/single"
  if ! "$PHOTON_BIN" render "$scene" --progressive --passes 0..8 --threads 2 "${args[@]}" \
    -o "$work/single/part-00000-00008.exr" --no-png >"$work/single/render.log" 2>&1 ||
    ! "$PHOTON_BIN" merge "$work/single/part-00000-00008.exr" -o "$work/single/image.exr" --no-png \
      >"$work/single/merge.log" 2>&1; then
    tail -n 5 "$work"/single/*.log >&2
    return 1
  fi
  echo "     one process, 8 passes + merge: $(since "$t0") s"
}

same_image() { # A B
  cmp "$work/$1/image.exr" "$work/$2/image.exr" &&
    echo "     $1/image.exr = $2/image.exr ($(wc -c <"$work/$1/image.exr") bytes)"
}

# A task that fails (photon rejects the argument) must get the merge job cancelled.
failing_run() {
  local t0
  t0=$(now)
  if submit_and_wait 60 "$scene" 8 2 "$work/failing" "${args[@]}" --no-such-flag; then
    echo "     merge job of a failing array completed" >&2; return 1
  fi
  local state
  state=$(scontrol show job -o "$MERGE_JOB" | grep -o 'JobState=[A-Z_]*')
  echo "     failing array: merge job $MERGE_JOB ended $state after $(since "$t0") s"
  [ "$state" = JobState=CANCELLED ] && [ ! -e "$work/failing/image.exr" ]
}

# Task 1 of the 4-task run, submitted again alone (as after a failure), writes the same part.
rerun_one_task() {
  local part=$work/four/parts/part-00002-00004.exr job
  mv "$part" "$work/four/part-00002-00004.first.exr"
  job=$(PHOTON_ARRAY_TASKS=4 sbatch --parsable --array=1 --export=ALL \
    --output="$work/four/logs/rerun-%A_%a.log" \
    contrib/slurm/render-array.sbatch "$PWD/$scene" 8 "$work/four" "${args[@]}") &&
    contrib/slurm/wait.sh "$job" "$timeout" >/dev/null &&
    cmp "$part" "$work/four/part-00002-00004.first.exr" &&
    echo "     task 1 of 4 run alone (job $job) wrote the same part-00002-00004.exr"
}

# merge.sbatch, run directly, must refuse parts that do not tile 0..8 (a pass range missing).
merge_refuses_gap() {
  local msg
  mkdir -p "$work/gap/parts"
  cp "$work"/four/parts/part-*.exr "$work/gap/parts/"
  rm "$work/gap/parts/part-00002-00004.exr"
  if msg=$(bash contrib/slurm/merge.sbatch "$work/gap" 8 2>&1); then
    echo "     merge.sbatch accepted parts without passes 2..4" >&2; return 1
  fi
  echo "     merge.sbatch: $msg"
  [[ $msg == *"passes 2..4 missing"* ]] && [ ! -e "$work/gap/image.exr" ]
}

# submit.sh must refuse an OUTDIR that already holds parts (and submit nothing).
submit_refuses_reuse() {
  local msg before
  before=$(squeue -h | wc -l)
  if msg=$(contrib/slurm/submit.sh "$scene" 8 4 "$work/four" "${args[@]}" 2>&1); then
    echo "     submit.sh accepted a used OUTDIR: $msg" >&2; return 1
  fi
  echo "     $msg"
  [[ $msg == *"already holds parts"* ]] && [ "$(squeue -h | wc -l)" = "$before" ]
}

# Hostile names, without the cluster. A part whose name holds `$(cmd)` in an arithmetic
# subscript ran cmd in merge.sbatch (issue 22, case 5); it must be refused, cmd not run.
merge_refuses_hostile_part_name() {
  local d=$work/hostile msg
  mkdir -p "$d/parts"
  : >"$d/parts/part-00000-00008.exr"
  : >"$d/parts/part-00000-00002+parts[\$(touch PWNED)].exr"
  if msg=$(cd "$d" && PHOTON_BIN=/bin/false bash "$OLDPWD/contrib/slurm/merge.sbatch" "$d" 8 2>&1); then
    echo "     merge.sbatch accepted a hostile part name" >&2; return 1
  fi
  echo "     merge.sbatch: $msg"
  [ ! -e "$d/PWNED" ] && [[ $msg == *"is not a part name"* ]]
}

# An OUTDIR with a space and a `*`: photon merge gets `--png OUTDIR/image.png` as two words,
# unsplit and unglobbed (it split and globbed).
merge_quotes_outdir() {
  local d="$work/out dir *" got
  mkdir -p "$d/parts"
  : >"$d/parts/part-00000-00008.exr"
  printf '#!/bin/sh\nfor a in "$@"; do printf "%%s\\n" "$a"; done >"$ARGS_FILE"\n' >"$work/argstub"
  chmod +x "$work/argstub"
  ARGS_FILE=$work/args PHOTON_BIN=$work/argstub bash contrib/slurm/merge.sbatch "$d" 8 >/dev/null || return 1
  got=$(tail -n 2 "$work/args")
  [ "$got" = "--png
$d/image.png" ] || { echo "     photon merge got: $(tr '\n' '|' <"$work/args")" >&2; return 1; }
  echo "     photon merge got the preview path as one word: $d/image.png"
}

# A comma in PHOTON_BIN's path must not reach sbatch's --export list, where it would start a
# new variable (issue 22, case 6). A fake sbatch records its arguments and environment.
submit_passes_bin_as_data() {
  local d=$work/fake bin
  bin="$d/a,LD_PRELOAD=evil.so/photon"
  mkdir -p "$d/path" "$(dirname "$bin")"
  printf '#!/bin/sh\nexit 0\n' >"$bin"
  chmod +x "$bin"
  printf '#!/bin/sh\nprintf "%%s\\n" "$@" >>"%s/sbatch.args"\nprintf "%%s\\n" "$PHOTON_BIN" >>"%s/sbatch.env"\necho 42\n' "$d" "$d" >"$d/path/sbatch"
  chmod +x "$d/path/sbatch"
  PATH="$d/path:$PATH" PHOTON_BIN=$bin contrib/slurm/submit.sh "$scene" 8 4 "$d/out" >/dev/null || return 1
  if grep -q LD_PRELOAD "$d/sbatch.args"; then
    echo "     sbatch arguments name LD_PRELOAD: $(grep -- --export "$d/sbatch.args")" >&2; return 1
  fi
  [ "$(sort -u "$d/sbatch.env")" = "$bin" ] && grep -qx -- --export=ALL "$d/sbatch.args" &&
    echo "     both sbatch calls: --export=ALL, PHOTON_BIN in the environment as one value"
}

daemons_running() {
  local n
  n=$(.ci/slurm ps "$SLURM_STATE" | grep -cE '^[0-9]+ (munged|slurmctld|slurmd) ')
  [ "$n" = 3 ] || { echo "     $n of the 3 daemons in ps" >&2; return 1; }
}

# After teardown: none of the PIDs seen before, and nothing naming the state directory, in ps.
nothing_left() { # STATE PIDS...
  local s=$1 left
  shift
  left=$( (ps -o pid=,args= -p "$(IFS=,; echo "$*")"; pgrep -af -- "$s/") 2>/dev/null)
  [ -z "$left" ] || { echo "     left behind: $left" >&2; return 1; }
  echo "     processes left: 0 (checked ${#@} PIDs and every command line)"
}

[ "$DRY" = 1 ] && echo "dry run: photon is a stub (tests/slurm-lib.sh: stub_photon)"
check "merge.sbatch refuses a hostile part name without running it" merge_refuses_hostile_part_name
check "merge.sbatch passes an OUTDIR with a space and * as one word" merge_quotes_outdir
check "submit.sh passes a PHOTON_BIN holding a comma as data" submit_passes_bin_as_data
check "cluster up" cluster_up || { summary; exit 1; }
echo "     cluster up in ${UP_SECONDS} s, package check/install included (state $SLURM_STATE)"
check "daemons running" daemons_running
state=$SLURM_STATE
pids=$(.ci/slurm ps "$state" | cut -d' ' -f1 | tr '\n' ' ')
if check "photon binary" photon_binary "$work"; then
  check "4-task array over 8 passes" array_run four 4
  check "4 parts" parts_are four 4
  # The 3-task run's folder name holds a space and a comma: names pass through submit.sh,
  # sbatch, both job scripts and photon as data on the real cluster (issue 22, cases 5-6).
  three="three tasks,x"
  check "3-task array over 8 passes (2+3+3), into '$three'" array_run "$three" 3
  check "3 parts" parts_are "$three" 3
  check "single-process render + merge" single_run
  check "4-task merge = single-process merge, bit for bit" same_image four single
  check "3-task merge = single-process merge, bit for bit" same_image "$three" single
  check "failing array cancels the merge" failing_run
  check "one task run again alone writes the same part" rerun_one_task
  check "merge.sbatch refuses a missing pass range" merge_refuses_gap
  check "submit.sh refuses a used output directory" submit_refuses_reuse
fi
check "cluster down" cluster_down
echo "     cluster down in ${DOWN_SECONDS:-?} s"
# shellcheck disable=SC2086 # a list of PIDs
check "no process left behind" nothing_left "$state" $pids
summary
