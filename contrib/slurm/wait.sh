#!/usr/bin/env bash
# Waits for a Slurm job to end and prints its final state (polls `scontrol show job`, which needs
# no accounting database; finished jobs stay visible for MinJobAge, 300 s by default).
#
#   contrib/slurm/wait.sh JOBID [TIMEOUT_SECONDS]   (default timeout 3600)
#
# Exit status: 0 if the job COMPLETED, 1 if it ended in any other state (FAILED, CANCELLED -
# e.g. a merge whose array failed -, TIMEOUT, ...) or vanished, 3 on timeout.
set -euo pipefail

[ $# -ge 1 ] || { echo "usage: wait.sh JOBID [TIMEOUT_SECONDS]" >&2; exit 2; }
job=$1 timeout=${2:-3600}
end=$(( $(date +%s) + timeout ))
# The states of the job (one line per task for an array job).
states() { scontrol show job -o "$job" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | sort -u; }
while :; do
  s=$(states)
  [ -n "$s" ] || { echo "job $job: unknown to scontrol (ended more than MinJobAge ago?)" >&2; exit 1; }
  if ! grep -qvxE 'COMPLETED|PENDING|CONFIGURING|RUNNING|COMPLETING|SUSPENDED|REQUEUED|RESIZING' <<<"$s"; then
    [ "$s" = COMPLETED ] && { echo "job $job COMPLETED"; exit 0; }
  else
    echo "job $job ended ${s//$'\n'/ }: $(scontrol show job -o "$job" | grep -o 'Reason=[^ ]*' | sort -u | tr '\n' ' ')" >&2
    exit 1
  fi
  [ "$(date +%s)" -lt "$end" ] || { echo "job $job still ${s//$'\n'/ } after $timeout s" >&2; exit 3; }
  sleep 0.2
done
