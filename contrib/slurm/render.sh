#!/usr/bin/env bash
# Recipe A: render one image on a Slurm cluster, split into TASKS rectangles.
#
#   render.sh [--wait] SCENE OUT.png TASKS [WORKDIR]
#
#   1. `rayoflight split SCENE --tasks TASKS`  -> WORKDIR/regions.txt
#   2. an array job, one task per region       -> WORKDIR/part-<i>.png    (region.sbatch)
#   3. after all tasks succeed (afterok)       -> OUT.png                 (assemble.sbatch)
#
# Prints the two job ids on stdout as shell assignments:
#   REGION_JOB=<id>
#   ASSEMBLE_JOB=<id>
# With --wait (or WAIT=1) it then waits for both (at most WAIT_TIMEOUT seconds,
# default 3600) and exits non-zero unless every job COMPLETED.
#
# Inputs (environment, all optional):
#   RAYOFLIGHT     the binary (default: rayoflight on PATH); made absolute and
#                  handed to the jobs
#   CPUS_PER_TASK  CPUs (and render threads) per array task (default 1: as many
#                  tasks at once as the cluster has CPUs)
#   RENDER_ARGS    render options for split and every task, such as
#                  "--aa 2 --set model.depth=8" (they change the cost and the
#                  pixels; the parts record them and assemble checks they agree)
#   WORKDIR        instead of the 4th argument (default: OUT without .png, plus .work)
# sbatch's own variables apply too, e.g. SBATCH_PARTITION, SBATCH_TIMELIMIT,
# SBATCH_ACCOUNT.  On a real cluster SCENE, WORKDIR, OUT and the binary must be
# on a file system every node sees, at the same path.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
usage="usage: $0 [--wait] SCENE OUT.png TASKS [WORKDIR]"

wait=${WAIT:-0}
if [[ ${1:-} == --wait ]]; then
    wait=1
    shift
fi
[[ $# -ge 3 && $# -le 4 ]] || { echo "$usage" >&2; exit 2; }

scene=$(realpath -e "$1")
out=$(realpath -m "$2")
tasks=$3
workdir=$(realpath -m "${4:-${WORKDIR:-${out%.png}.work}}")
cpus_per_task=${CPUS_PER_TASK:-1}
[[ $tasks =~ ^[1-9][0-9]*$ ]] || { echo "TASKS must be a positive number, not '$tasks'" >&2; exit 2; }

# The jobs get the binary by absolute path: they may start with another PATH.
RAYOFLIGHT=${RAYOFLIGHT:-rayoflight}
bin=$(command -v "$RAYOFLIGHT") || { echo "rayoflight binary '$RAYOFLIGHT' not found" >&2; exit 1; }
RAYOFLIGHT=$(realpath -e "$bin")
export RAYOFLIGHT

mkdir -p "$workdir/logs" "$(dirname "$out")"
# Nothing from an earlier run may pass for this one's result.
rm -f "$workdir"/part-*.png "$out"

# The render's options, split into words: split estimates the cost with them,
# every task renders with them.
read -ra render_args <<<"${RENDER_ARGS:-}"

# 1. The regions, one line each, computed here on the submit host.
"$RAYOFLIGHT" split "$scene" --tasks "$tasks" "${render_args[@]}" >"$workdir/regions.txt"
count=$(grep -c . "$workdir/regions.txt" || true)
if ((count == 0)); then
    echo "rayoflight split printed no regions" >&2
    exit 1
fi
if ((count != tasks)); then
    echo "note: split made $count regions for $tasks tasks; submitting $count" >&2
fi

# --parsable prints "JOBID" or "JOBID;CLUSTER".
submit() {
    local id
    id=$(sbatch --parsable "$@")
    echo "${id%%;*}"
}

# 2. One array task per region.  --export=ALL passes RAYOFLIGHT (and SLURM_CONF
#    etc.) on; --chdir and the log paths are absolute.
region_job=$(submit \
    --array="0-$((count - 1))" \
    --cpus-per-task="$cpus_per_task" \
    --chdir="$workdir" \
    --output="$workdir/logs/region-%A_%a.out" \
    --export=ALL \
    "$here/region.sbatch" "$scene" "$workdir" "${render_args[@]}")

# 3. The assembly, once every task has succeeded.  If one fails, afterok can
#    never be met: --kill-on-invalid-dep=yes cancels the job instead of leaving
#    it pending for ever.
assemble_job=$(submit \
    --dependency="afterok:$region_job" \
    --kill-on-invalid-dep=yes \
    --chdir="$workdir" \
    --output="$workdir/logs/assemble-%j.out" \
    --export=ALL \
    "$here/assemble.sbatch" "$out" "$workdir" "$count")

echo "render: $count region tasks in array job $region_job, assembly job $assemble_job -> $out (logs: $workdir/logs)" >&2
echo "REGION_JOB=$region_job"
echo "ASSEMBLE_JOB=$assemble_job"

if ((wait)); then
    "$here/wait-jobs.sh" -t "${WAIT_TIMEOUT:-3600}" "$region_job" "$assemble_job" >&2
fi
