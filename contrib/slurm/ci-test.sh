#!/usr/bin/env bash
# CI test of the Slurm recipes on a real, throw-away, single-node Slurm cluster.
#
#   sudo contrib/slurm/ci-test.sh RAYOFLIGHT_BINARY [SCENE]
#
# Needs root and (Debian/Ubuntu):
#   apt-get install -y --no-install-recommends slurmctld slurmd slurm-client munge
#
# What it does:
#   1. starts a cluster in a temporary directory (local-cluster.sh); an EXIT
#      trap stops it again, by the PIDs it recorded, whatever happens;
#   2. recipe A (render.sh): SCENE split into $TASKS (default 5) regions, one
#      array task each, then the assembly job;
#   3. recipe B (sweep.sh): one render per value of $SWEEP_PATH (default
#      camera.eyeDistance: $SWEEP_VALUES, default "3 4 5"), then the contact sheet;
#   4. waits for all four jobs (at most $TIMEOUT seconds, default 300), and
#      requires every job and array task to have ended COMPLETED, exit code 0:0;
#   5. requires the assembled image to be byte for byte the image a plain
#      one-machine render (`rayoflight SCENE -out one-machine.png --quiet
#      $RENDER_ARGS`; recipe A renders with $RENDER_ARGS too)
#      writes, every sweep image to exist and differ from the others, and the
#      sheet to be a PNG.
# On failure it prints the daemons' logs and the jobs' output, and keeps the
# temporary directory (KEEP=1 keeps it on success too).  Exit status 0 only if
# everything passed.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
repo=$(cd "$here/../.." && pwd -P)

if [[ $# -lt 1 || $# -gt 2 ]]; then
    echo "usage: $0 RAYOFLIGHT_BINARY [SCENE]" >&2
    exit 2
fi
RAYOFLIGHT=$(realpath -e "$1")
[[ -x $RAYOFLIGHT ]] || { echo "$RAYOFLIGHT is not executable" >&2; exit 2; }
export RAYOFLIGHT
scene_src=$(realpath -e "${2:-$repo/scenes/example.xml}")

TASKS=${TASKS:-5}
SWEEP_PATH=${SWEEP_PATH:-camera.eyeDistance}
SWEEP_VALUES=${SWEEP_VALUES:-3 4 5}
TIMEOUT=${TIMEOUT:-300}

[[ $(id -u) -eq 0 ]] || { echo "$0 must run as root (it starts munged, slurmctld and slurmd)" >&2; exit 2; }

say() { echo "=== ci-test [$((SECONDS))s]: $*"; }
fail() { echo "=== ci-test: FAIL: $*" >&2; exit 1; }

# A short path: munged's socket lives below it (unix socket paths are limited
# to 108 bytes).
tmp=$(mktemp -d /tmp/rol-slurm.XXXXXX)
cluster=$tmp/cluster
jobs=()
child=""

# run CMD...: runs CMD in the background and waits for it.  bash runs a trap
# only once a foreground command ends; `wait` is cut short at once, so a
# SIGTERM or ^C from CI cleans up right away instead of after a long render.
run() {
    "$@" &
    child=$!
    local rc=0
    wait "$child" || rc=$?
    child=""
    return "$rc"
}

dump() {
    echo "----- diagnostics ($tmp) -----"
    local f
    # Daemons' state, and if the controller still runs, the queue and the jobs.
    if "$here/local-cluster.sh" status "$cluster" && [[ -f $cluster/env ]]; then
        # shellcheck disable=SC1091
        (source "$cluster/env"
         timeout 10 squeue || true
         for j in "${jobs[@]}"; do timeout 10 scontrol show job -o "$j" || true; done)
    fi
    for f in "$cluster"/log/slurmctld.log "$cluster"/log/slurmd.log "$cluster"/log/munged.log; do
        [[ -f $f ]] || continue
        echo "----- $f (last 60 lines) -----"
        tail -n 60 "$f"
    done
    for f in "$cluster"/log/jobcomp.log "$tmp"/*/logs/*; do
        [[ -f $f ]] || continue
        echo "----- $f -----"
        cat "$f"
    done
}

cleanup() {
    local rc=$?
    trap - EXIT INT TERM
    set +e
    if [[ -n $child ]]; then
        kill -TERM "$child" 2>/dev/null
        wait "$child" 2>/dev/null
    fi
    if ((rc != 0)); then
        dump >&2
    fi
    "$here/local-cluster.sh" stop "$cluster"
    if ((rc == 0)) && [[ ${KEEP:-0} != 1 ]]; then
        rm -rf "$tmp"
    else
        echo "=== ci-test: files kept in $tmp" >&2
    fi
    if ((rc == 0)); then say "PASS"; else echo "=== ci-test: FAILED (exit $rc)" >&2; fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

say "binary $RAYOFLIGHT, scene $scene_src, work in $tmp"

# --- 1. the cluster ----------------------------------------------------------
"$here/local-cluster.sh" start "$cluster" >/dev/null
# shellcheck disable=SC1091
source "$cluster/env"
sinfo

# The scene is copied, so the test reads the same file from start to end.
scene=$tmp/scene.xml
cp "$scene_src" "$scene"

# --- 2 and 3. submit both recipes ------------------------------------------------
say "recipe A: render.sh with $TASKS tasks"
ids=$("$here/render.sh" "$scene" "$tmp/render/out.png" "$TASKS" "$tmp/render")
echo "$ids"
region_job=$(sed -n 's/^REGION_JOB=//p' <<<"$ids")
assemble_job=$(sed -n 's/^ASSEMBLE_JOB=//p' <<<"$ids")
[[ -n $region_job && -n $assemble_job ]] || fail "render.sh printed no job ids"
jobs+=("$region_job" "$assemble_job")

say "recipe B: sweep.sh over $SWEEP_PATH = $SWEEP_VALUES"
tr ' ' '\n' <<<"$SWEEP_VALUES" >"$tmp/values.txt"
ids=$("$here/sweep.sh" "$scene" "$SWEEP_PATH" "$tmp/values.txt" "$tmp/sweep/sheet.png" "$tmp/sweep")
echo "$ids"
sweep_job=$(sed -n 's/^SWEEP_JOB=//p' <<<"$ids")
sheet_job=$(sed -n 's/^SHEET_JOB=//p' <<<"$ids")
[[ -n $sweep_job && -n $sheet_job ]] || fail "sweep.sh printed no job ids"
jobs+=("$sweep_job" "$sheet_job")

# The reference, rendered here on one machine while the cluster works.
left() { local s=$((TIMEOUT - SECONDS)); echo $((s > 0 ? s : 1)); }
say "one-machine render (reference)"
read -ra render_args <<<"${RENDER_ARGS:-}"
run timeout "$(left)" "$RAYOFLIGHT" "$scene" -out "$tmp/one-machine.png" --quiet "${render_args[@]}" ||
    fail "the one-machine render failed or did not end within ${TIMEOUT}s"

# --- 4. wait -------------------------------------------------------------------
remaining=$(left)
say "waiting for jobs ${jobs[*]} (at most ${remaining}s)"
if run "$here/wait-jobs.sh" -t "$remaining" "${jobs[@]}"; then
    :
else
    rc=$?
    ((rc == 2)) && fail "jobs did not end within ${TIMEOUT}s"
    fail "not every job COMPLETED"
fi

# --- 5. the results ------------------------------------------------------------
is_png() { [[ $(od -An -tx1 -N8 "$1" | tr -d ' \n') == 89504e470d0a1a0a ]]; }

parts=("$tmp"/render/part-*.png)
[[ ${#parts[@]} -eq $TASKS ]] || fail "expected $TASKS parts, found ${#parts[@]}"
[[ -s $tmp/render/out.png ]] || fail "recipe A wrote no $tmp/render/out.png"
cmp "$tmp/render/out.png" "$tmp/one-machine.png" ||
    fail "the assembled image differs from the one-machine render"
say "assembled image == one-machine render ($(stat -c %s "$tmp/one-machine.png") bytes)"

mapfile -t images < <(cut -f1 "$tmp/sweep/sweep.tsv")
[[ ${#images[@]} -eq $(wc -w <<<"$SWEEP_VALUES") ]] || fail "sweep manifest lists ${#images[@]} images"
for ((i = 0; i < ${#images[@]}; i++)); do
    is_png "${images[i]}" || fail "${images[i]} is missing or not a PNG"
    for ((j = 0; j < i; j++)); do
        ! cmp -s "${images[i]}" "${images[j]}" ||
            fail "${images[i]} and ${images[j]} are the same: --set $SWEEP_PATH had no effect"
    done
done
say "sweep images: $(basename -a "${images[@]}" | tr '\n' ' ')"
is_png "$tmp/sweep/sheet.png" || fail "the contact sheet is missing or not a PNG"
say "contact sheet $(stat -c %s "$tmp/sweep/sheet.png") bytes"
