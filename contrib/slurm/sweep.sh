#!/usr/bin/env bash
# Recipe B: render a scene once per value of one setting, on a Slurm cluster,
# and put the results on a contact sheet.
#
#   sweep.sh [--wait] SCENE PATH VALUES_FILE SHEET.png [WORKDIR]
#
#   PATH         a scene value as `rayoflight --set` names it, e.g.
#                camera.eyeDistance or object[1].material.ka
#   VALUES_FILE  one value a line (blank lines and lines starting with # are skipped)
#
#   1. an array job, one task per value: rayoflight SCENE --set PATH=VALUE
#      -> WORKDIR/<i>-<PATH>=<VALUE>.png   (sweep-render.sbatch; the name, made
#         safe for a file name, is the image's label on the sheet)
#   2. after all tasks succeed (afterok): rayoflight sheet -> SHEET.png (sheet.sbatch)
#
# WORKDIR/sweep.tsv lists "FILE<TAB>VALUE" for each task, in order.
# Prints the two job ids on stdout as shell assignments:
#   SWEEP_JOB=<id>
#   SHEET_JOB=<id>
# With --wait (or WAIT=1) it then waits for both (at most WAIT_TIMEOUT seconds,
# default 3600) and exits non-zero unless every job COMPLETED.
#
# Inputs (environment, all optional):
#   RAYOFLIGHT     the binary (default: rayoflight on PATH)
#   CPUS_PER_TASK  CPUs (and render threads) per render (default 1)
#   SHEET_COLUMNS  --columns for the sheet (default: rayoflight's choice)
#   WORKDIR        instead of the 5th argument (default: SHEET without .png, plus .work)
# sbatch's own variables (SBATCH_PARTITION, SBATCH_TIMELIMIT, ...) apply too.
# On a real cluster every path must be on a file system every node sees.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
usage="usage: $0 [--wait] SCENE PATH VALUES_FILE SHEET.png [WORKDIR]"

wait=${WAIT:-0}
if [[ ${1:-} == --wait ]]; then
    wait=1
    shift
fi
[[ $# -ge 4 && $# -le 5 ]] || { echo "$usage" >&2; exit 2; }

scene=$(realpath -e "$1")
path=$2
values_file=$3
sheet=$(realpath -m "$4")
workdir=$(realpath -m "${5:-${WORKDIR:-${sheet%.png}.work}}")
cpus_per_task=${CPUS_PER_TASK:-1}
[[ -n $path && $path != *=* ]] || { echo "PATH must be a scene path such as camera.eyeDistance, not '$path'" >&2; exit 2; }
[[ -r $values_file ]] || { echo "cannot read VALUES_FILE $values_file" >&2; exit 2; }

RAYOFLIGHT=${RAYOFLIGHT:-rayoflight}
bin=$(command -v "$RAYOFLIGHT") || { echo "rayoflight binary '$RAYOFLIGHT' not found" >&2; exit 1; }
RAYOFLIGHT=$(realpath -e "$bin")
export RAYOFLIGHT

mkdir -p "$workdir/logs" "$(dirname "$sheet")"
rm -f "$sheet"

# The values, without blank lines, comments and surrounding blanks.
values=()
while IFS= read -r value || [[ -n $value ]]; do
    value=${value%$'\r'}
    value=$(sed 's/^[[:space:]]*//; s/[[:space:]]*$//' <<<"$value")
    [[ -z $value || $value == \#* ]] && continue
    [[ $value != *$'\t'* ]] || { echo "a value may not contain a tab: '$value'" >&2; exit 2; }
    values+=("$value")
done <"$values_file"
count=${#values[@]}
((count > 0)) || { echo "no values in $values_file" >&2; exit 1; }

# The manifest: one "FILE<TAB>VALUE" line per task.  The file name is
# <i>-<PATH>=<VALUE>.png (e.g. 0-object[1].material.ka=0.4.png) with every
# character other than letters, digits and . _ + - = [ ] turned into _ (so no
# / or space or quote), the index zero-padded so that names sort in sweep order.
manifest=$workdir/sweep.tsv
width=${#count}
: >"$manifest"
for ((i = 0; i < count; i++)); do
    name=$(printf '%0*d-%s=%s' "$width" "$i" "$path" "${values[i]}" | sed 's/[^][A-Za-z0-9._+=-]/_/g')
    printf '%s\t%s\n' "$workdir/$name.png" "${values[i]}" >>"$manifest"
done

submit() {
    local id
    id=$(sbatch --parsable "$@")
    echo "${id%%;*}"
}

# 1. One render per value.
sweep_job=$(submit \
    --array="0-$((count - 1))" \
    --cpus-per-task="$cpus_per_task" \
    --chdir="$workdir" \
    --output="$workdir/logs/sweep-%A_%a.out" \
    --export=ALL \
    "$here/sweep-render.sbatch" "$scene" "$path" "$manifest")

# 2. The contact sheet, once every render has succeeded (cancelled if one fails).
sheet_job=$(submit \
    --dependency="afterok:$sweep_job" \
    --kill-on-invalid-dep=yes \
    --chdir="$workdir" \
    --output="$workdir/logs/sheet-%j.out" \
    --export=ALL \
    "$here/sheet.sbatch" "$sheet" "$manifest" ${SHEET_COLUMNS:+"$SHEET_COLUMNS"})

echo "sweep: $count renders of $path in array job $sweep_job, sheet job $sheet_job -> $sheet (logs: $workdir/logs)" >&2
echo "SWEEP_JOB=$sweep_job"
echo "SHEET_JOB=$sheet_job"

if ((wait)); then
    "$here/wait-jobs.sh" -t "${WAIT_TIMEOUT:-3600}" "$sweep_job" "$sheet_job" >&2
fi
