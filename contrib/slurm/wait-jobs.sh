#!/usr/bin/env bash
# Wait, with a time limit, until Slurm jobs have ended, and say how they ended.
#
#   wait-jobs.sh [-t SECONDS] JOBID...
#
# A JOBID may be an array job: then every one of its tasks is waited for.
# Works without accounting (no sacct): it polls `scontrol show job`, which
# knows a finished job for MinJobAge seconds (300 by default; local-cluster.sh
# sets 3600), far longer than the poll interval.
#
# Prints one line per job (or array task) at the end: "JOBID STATE EXITCODE".
# Exit status: 0 if every job ended COMPLETED with exit code 0:0,
#              1 if any job ended otherwise (FAILED, CANCELLED, TIMEOUT, ...,
#                or a dependency that can never be satisfied),
#              2 on timeout (SECONDS, default $WAIT_TIMEOUT or 3600) or misuse.
set -euo pipefail

timeout=${WAIT_TIMEOUT:-3600}
interval=${WAIT_INTERVAL:-2}
if [[ ${1:-} == -t ]]; then
    timeout=$2
    shift 2
fi
if [[ $# -eq 0 ]]; then
    echo "usage: $0 [-t SECONDS] JOBID..." >&2
    exit 2
fi

# field NAME LINE: the value of NAME=... in a one-line `scontrol show job -o` record.
field() { sed -n "s/.*[[:space:]]$1=\([^[:space:]]*\).*/\1/p; s/^$1=\([^[:space:]]*\).*/\1/p" <<<"$2" | head -n1; }

# snapshot: fills `records` with "ID STATE EXITCODE REASON" for every job and
# array task; sets `pending` to how many have not ended yet.
snapshot() {
    records=()
    pending=0
    local job out line id state exitcode reason array task
    for job in "$@"; do
        if ! out=$(scontrol show job -o "$job" 2>&1); then
            # Unknown to slurmctld: never submitted, or purged long ago.
            records+=("$job UNKNOWN - ${out//[[:space:]]/_}")
            continue
        fi
        while IFS= read -r line; do
            [[ -n $line ]] || continue
            id=$(field JobId "$line")
            array=$(field ArrayJobId "$line")
            task=$(field ArrayTaskId "$line")
            [[ -n $array && -n $task ]] && id=${array}_$task
            state=$(field JobState "$line")
            exitcode=$(field ExitCode "$line")
            reason=$(field Reason "$line")
            records+=("$id $state ${exitcode:--} ${reason:--}")
            case $state in
                COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | PREEMPTED | OUT_OF_MEMORY | BOOT_FAIL | DEADLINE) ;;
                PENDING)
                    # afterok on a job that failed: without --kill-on-invalid-dep
                    # the job would wait forever; count it as ended.
                    [[ $reason == DependencyNeverSatisfied ]] || pending=$((pending + 1))
                    ;;
                *) pending=$((pending + 1)) ;;
            esac
        done <<<"$out"
    done
}

deadline=$((SECONDS + timeout))
last=""
while :; do
    snapshot "$@"
    # A one-line progress report on stderr whenever the picture changes.
    summary=$(printf '%s\n' "${records[@]}" | awk '{ print $2 }' | sort | uniq -c | awk '{ printf "%s %s, ", $1, $2 }')
    if [[ $summary != "$last" ]]; then
        echo "wait-jobs: [${SECONDS}s] ${summary%, }" >&2
        last=$summary
    fi
    ((pending == 0)) && break
    if ((SECONDS >= deadline)); then
        echo "wait-jobs: timed out after ${timeout}s; still not ended:" >&2
        printf '%s\n' "${records[@]}" >&2
        exit 2
    fi
    sleep "$interval"
done

rc=0
for record in "${records[@]}"; do
    read -r id state exitcode reason <<<"$record"
    echo "$id $state $exitcode"
    if [[ $state != COMPLETED || $exitcode != 0:0 ]]; then
        echo "wait-jobs: job $id ended $state (exit code $exitcode, reason $reason)" >&2
        rc=1
    fi
done
exit $rc
