#!/usr/bin/env bash
# The figures of docs/cluster.md, measured on this machine: a SIZE x SIZE
# render of a bench scene (default: mirrors at 16000x16000) once whole, then
# split into each of TASKS regions (default 8 64 512), every region rendered
# by its own process as a cluster task would (-time: the render; wall: the
# whole process, loading the scene and writing the part), and the parts
# assembled (/usr/bin/time: wall time and peak memory). Prints one CSV line
# per run on stdout and a summary per task count on stderr; the files stay
# in OUT_DIR.
# Usage: tools/measure-cluster.sh [OUT_DIR [SIZE [SCENE [TASKS...]]]]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-/tmp/measure-cluster}
size=${2:-16000}
scene=${3:-scenes/bench/mirrors.xml}
shift $(($# < 3 ? $# : 3))
counts=("$@")
[ ${#counts[@]} -gt 0 ] || counts=(8 64 512)
bin=$PWD/target/release/rayoflight
[ -x "$bin" ] || cargo build --release
mkdir -p "$out"
set_size=(--set "camera.width=$size" --set "camera.height=$size")

now() { date +%s%N; }
echo "run,tasks,region,render_ns,wall_ns,peak_kb"

start=$(now)
whole_ns=$("$bin" "$scene" "${set_size[@]}" -out "$out/whole.png" -time -q | sed 's/render: \([0-9]*\) ns/\1/')
whole_wall=$(($(now) - start))
echo "whole,1,\"0,0,$size,$size\",$whole_ns,$whole_wall,"
echo "whole: render $((whole_ns / 1000000)) ms, process $((whole_wall / 1000000)) ms" >&2

for tasks in "${counts[@]}"; do
    dir=$out/tasks-$tasks
    rm -rf "$dir" && mkdir -p "$dir"
    start=$(now)
    "$bin" split "$scene" "${set_size[@]}" --tasks "$tasks" >"$dir/regions.txt"
    split_wall=$(($(now) - start))
    echo "split,$tasks,,,$split_wall,"
    k=0 slowest=0 sum=0
    while read -r region; do
        start=$(now)
        ns=$("$bin" "$scene" "${set_size[@]}" --region "$region" -out "$dir/part-$k.png" -time -q |
            sed 's/render: \([0-9]*\) ns/\1/')
        wall=$(($(now) - start))
        echo "region,$tasks,\"$region\",$ns,$wall,"
        ((wall > slowest)) && slowest=$wall
        sum=$((sum + wall))
        k=$((k + 1))
    done <"$dir/regions.txt"
    parts=()
    for ((i = 0; i < k; i++)); do parts+=("$dir/part-$i.png"); done
    start=$(now)
    /usr/bin/time -f "%M" -o "$dir/assemble.rss" "$bin" assemble -out "$dir/assembled.png" "${parts[@]}"
    assemble_wall=$(($(now) - start))
    peak=$(tail -n 1 "$dir/assemble.rss")
    echo "assemble,$tasks,,,$assemble_wall,$peak"
    same=no
    cmp -s "$dir/assembled.png" "$out/whole.png" && same=yes
    echo "tasks $tasks: split $((split_wall / 1000000)) ms; regions: slowest $((slowest / 1000000)) ms, mean $((sum / k / 1000000)) ms, sum $((sum / 1000000)) ms; assemble $((assemble_wall / 1000000)) ms, peak ${peak} kB; same file as whole: $same" >&2
    rm -f "$dir"/part-*.png "$dir/assembled.png"
done
