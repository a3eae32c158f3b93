# Shared by tests/slurm.sh and benches/slurm-split.sh (source it from the repository root):
# a throw-away cluster that is always torn down, the photon binary or a stub of it, and one
# timed submit-and-wait of contrib/slurm/submit.sh.
# shellcheck shell=bash disable=SC2034 # the variables set here are read by the callers

now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }'; }

SLURM_STATE=""
# Brings up .ci/slurm's cluster, exports SLURM_CONF and makes sure it comes down on exit.
# Sets UP_SECONDS.
cluster_up() {
  local t0 out
  t0=$(now)
  out=$(.ci/slurm up) || return 1
  UP_SECONDS=$(since "$t0")
  SLURM_STATE=$(sed -n 's/^state=//p' <<<"$out")
  export SLURM_CONF=$SLURM_STATE/slurm.conf
  trap 'cluster_down_on_exit' EXIT
  trap 'exit 130' INT
  trap 'exit 143' TERM
}

# Tears the cluster down (if it is up); sets DOWN_SECONDS. Fails if processes were left behind.
cluster_down() {
  local t0
  [ -n "$SLURM_STATE" ] || return 0
  t0=$(now)
  .ci/slurm down "$SLURM_STATE" || { SLURM_STATE=""; return 1; }
  DOWN_SECONDS=$(since "$t0")
  SLURM_STATE=""
}

cluster_down_on_exit() {
  local rc=$?
  cluster_down || rc=1
  exit "$rc"
}

# A stand-in for `photon render --progressive --passes A..B` and `photon merge`, to test the
# cluster plumbing without the renderer: a "part" holds one line per pass, a function of the
# scene's bytes and the pass index only; merge sorts the lines by pass and refuses a pass range
# that is not exactly 0..N-1 with each pass once. Unknown arguments are errors, as in photon.
stub_photon() {
  local cmd=${1:-} scene="" range="" out="" png="" a b k h parts=()
  shift || true
  case "$cmd" in
    render)
      scene=$1; shift
      while [ $# -gt 0 ]; do
        case "$1" in
          --passes) range=$2; shift 2 ;;
          -o) out=$2; shift 2 ;;
          --threads | --res | --spp | --pass-spp | --alpha | --seed | --global-photons | --caustic-photons) shift 2 ;;
          --progressive | --no-png) shift ;;
          *) echo "error: unexpected argument '$1'" >&2; return 2 ;;
        esac
      done
      [ -r "$scene" ] || { echo "$scene: cannot read" >&2; return 2; }
      a=${range%..*} b=${range#*..}
      h=$(sha256sum <"$scene" | cut -c1-16)
      for ((k = a; k < b; k++)); do
        echo "pass $k $(echo "$h $k" | sha256sum | cut -c1-16)"
      done >"$out.tmp"
      mv "$out.tmp" "$out" ;;
    merge)
      while [ $# -gt 0 ]; do
        case "$1" in
          -o) out=$2; shift 2 ;;
          --png) png=$2; shift 2 ;;
          --no-png) shift ;;
          *) parts+=("$1"); shift ;;
        esac
      done
      sort -n -k2 "${parts[@]}" >"$out.tmp"
      awk '$2 != NR - 1 { print "merge: pass " NR - 1 " missing or repeated" > "/dev/stderr"; exit 1 }' "$out.tmp"
      mv "$out.tmp" "$out"
      [ -z "$png" ] || cp "$out" "$png" ;;
    *) echo "stub photon: unknown command '$cmd'" >&2; return 2 ;;
  esac
}

# Sets PHOTON_BIN: the stub written to DIR/photon-stub with DRY=1, else the release binary,
# built if needed.
photon_binary() { # DIR
  if [ "${DRY:-0}" = 1 ]; then
    PHOTON_BIN=$1/photon-stub
    { echo '#!/usr/bin/env bash'; echo 'set -euo pipefail'; declare -f stub_photon; echo 'stub_photon "$@"'; } >"$PHOTON_BIN"
    chmod +x "$PHOTON_BIN"
  else
    cargo build --release --quiet --bin photon || return 1
    PHOTON_BIN=$PWD/target/release/photon
    "$PHOTON_BIN" merge --help >/dev/null 2>&1 ||
      { echo "$PHOTON_BIN has no 'merge' subcommand yet (progressive rendering not on this branch); try --dry" >&2; return 1; }
  fi
  export PHOTON_BIN
}

# Submits SCENE PASSES TASKS OUTDIR [render args] and waits (TIMEOUT seconds) for the merge job.
# Sets ARRAY_JOB, MERGE_JOB and RUN_SECONDS (submit to merged image). Fails if the merge fails.
submit_and_wait() { # TIMEOUT SCENE PASSES TASKS OUTDIR [render args]
  local timeout=$1 t0 out
  shift
  t0=$(now)
  out=$(contrib/slurm/submit.sh "$@") || return 1
  ARRAY_JOB=$(sed -n 's/^array=//p' <<<"$out")
  MERGE_JOB=$(sed -n 's/^merge=//p' <<<"$out")
  contrib/slurm/wait.sh "$MERGE_JOB" "$timeout" >/dev/null || { RUN_SECONDS=$(since "$t0"); return 1; }
  RUN_SECONDS=$(since "$t0")
}
