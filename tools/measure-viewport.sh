#!/usr/bin/env bash
# Measures the viewport the way the issue asks, on this machine: pictures
# per second while orbiting (room.xml and a 4000x4000 scene), UI frames per
# second during a 4000x4000 render, idle CPU, and the time from releasing
# the mouse to the full picture; then the app's full picture against the
# command line's -time on the same scene (the mirrors at 2880x2160), with
# the UI's frames a second while it renders. Drives the release build under
# Xvfb with xdotool and reads the app's RAYOFLIGHT_STATS lines.
# Usage: tools/measure-viewport.sh [OUT_DIR [SCENE...]]   (needs xvfb, xdotool)
#        tools/measure-viewport.sh OUT_DIR --render [SCENE...]
# With scenes, measures those instead (a million spheres, say); with
# --render, only the app against the command line, on those scenes.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-/tmp/measure-viewport}
mkdir -p "$out"
bin=target/release/rayoflight
[ -x "$bin" ] || cargo build --release

# A floor, 30 spheres, three lights, whitted depth 5, 4000x4000.
big="$out/big-4000.xml"
{
  echo '<scene>'
  echo '  <plane><color red="0.8" green="0.8" blue="0.8"/><material ks="0.3"/><transformation><rotate-x angle="1.5707963"/><translate y="1"/></transformation></plane>'
  for i in $(seq 0 29); do
    x=$(( (i % 6) * 2 - 5 )); z=$(( (i / 6) * 2 ))
    echo "  <sphere><color red=\"0.$((i % 9 + 1))\" green=\"0.5\" blue=\"0.$(((i * 7) % 9 + 1))\"/><material ks=\"0.4\"/><transformation><scale factor=\"0.6\"/><translate x=\"$x\" y=\"0.4\" z=\"$z\"/></transformation></sphere>"
  done
  echo '  <light x="-5" y="-8" z="-5"/><light x="5" y="-8" z="-5"/><light x="0" y="-10" z="10"/>'
  echo '  <camera width="4000" height="4000" eyeDistance="2"><transformation><rotate-x angle="-0.3"/><translate y="-4" z="-12"/></transformation></camera>'
  echo '  <model type="whitted" depth="5"/>'
  echo '</scene>'
} > "$big"

display=:93
Xvfb $display -screen 0 1280x900x24 -nolisten tcp >/dev/null 2>&1 &
xvfb=$!
trap 'kill $xvfb 2>/dev/null || true' EXIT
sleep 1
export DISPLAY=$display LIBGL_ALWAYS_SOFTWARE=1 XDG_CONFIG_HOME=$out

# start_app SCENE LOG: starts the app on SCENE with its stats going to LOG,
# waits (at most 300 s) for its first full picture and focuses its window.
# Sets app (its pid) and waited (the seconds it took).
start_app() {
  local scene=$1 log=$2
  RAYOFLIGHT_STATS=1 "$bin" "$scene" 2>"$log" &
  app=$!
  local start=$SECONDS
  until grep -q "full picture" "$log"; do
    sleep 0.5
    if (( SECONDS - start > 300 )); then echo "$scene: no full picture in 300 s"; break; fi
  done
  waited=$((SECONDS - start))
  xdotool windowfocus --sync "$(xdotool search --name RayOfLight | head -n 1)"
}

# run SCENE NAME: start the app, wait for its first full picture, orbit for
# 4 s, release, then stay idle for 6 s.
run() {
  local name=$2 log="$out/$2.log"
  start_app "$1" "$log"
  echo "== $name: first full picture after $waited s (render stats before the drag:)"
  grep "stats: fps" "$log" | tail -n 3 || true
  local cx=780 cy=450
  : > "$out/$name.drag-start"
  local mark
  mark=$(wc -l < "$log")
  xdotool mousemove $cx $cy mousedown 1
  for k in $(seq 1 130); do
    xdotool mousemove $((cx + (k % 60) * 3)) $cy
    sleep 0.03
  done
  local during
  during=$(tail -n +"$mark" "$log" | grep "stats: fps" || true)
  mark=$(wc -l < "$log")
  xdotool mouseup 1
  sleep 8
  echo "-- during the orbit (one line a second: UI frames/s, pictures/s):"
  echo "$during"
  echo "-- after the release:"
  tail -n +"$mark" "$log" | grep "full picture" | head -n 1 || true
  local t0 t1
  t0=$(awk '{print $14 + $15}' /proc/$app/stat)
  sleep 5
  t1=$(awk '{print $14 + $15}' /proc/$app/stat)
  echo "-- idle CPU over 5 s: $(( (t1 - t0) * 100 / 500 )) % (ticks $t0 -> $t1)"
  kill $app
  wait $app 2>/dev/null || true
}

# The mirrors of the bench at 2880x2160 (four times its pixels).
mirrors="$out/mirrors-2880.xml"
sed 's/width="1440" height="1080"/width="2880" height="2160"/' scenes/bench/mirrors.xml > "$mirrors"

median() { sort -n | awk '{v[NR] = $1} END {if (NR) print v[int((NR + 1) / 2)]}'; }

# compare SCENE NAME: the app's first full picture, then five rounds of the
# command line's -time and the app's picture asked again with F5 (render
# again), one after the other so that both see the same load: the app from
# its request to the full picture (every pass), with the frames the window
# drew meanwhile. Medians of the five.
compare() {
  local scene=$1 name=$2 log="$out/$2.render.log"
  start_app "$scene" "$log"
  xdotool mousemove 1200 860
  sleep 2
  local cli=()
  for k in 1 2 3 4 5; do
    cli+=("$("$bin" -time "$scene" 2>&1 | sed -n 's/^render: \([0-9]*\) ns.*/\1/p')")
    local seen
    seen=$(grep -c "full picture" "$log")
    xdotool key F5
    until (( $(grep -c "full picture" "$log") > seen )); do sleep 0.2; done
    sleep 1
  done
  kill $app
  wait $app 2>/dev/null || true
  local lines ms fps cli_ms
  lines=$(grep "full picture" "$log" | tail -n 5)
  cli_ms=$(printf '%s\n' "${cli[@]}" | median | awk '{printf "%.1f", $1 / 1e6}')
  ms=$(sed -n 's/.*full picture \([0-9.]*\) ms.*/\1/p' <<<"$lines" | median)
  fps=$(sed -n 's/.*(\([0-9.]*\) frames\/s).*/\1/p' <<<"$lines" | median)
  echo "== $name: command line -time $cli_ms ms; app full picture $ms ms (request to full picture, every pass); medians of 5"
  echo "   ratio app/cli: $(awk -v a="$ms" -v c="$cli_ms" 'BEGIN {printf "%.2f", a / c}'); UI frames/s while the app rendered: median $fps"
  echo "   command line ns: ${cli[*]}"
  echo "$lines"
  echo "   load average: $(cut -d' ' -f1-3 /proc/loadavg)"
}

if [[ ${2:-} == --render ]]; then
  if (( $# > 2 )); then
    for scene in "${@:3}"; do compare "$scene" "$(basename "$scene" .xml)"; done
  else
    compare "$mirrors" mirrors-2880
  fi
elif (( $# > 1 )); then
  for scene in "${@:2}"; do
    run "$scene" "$(basename "$scene" .xml)"
  done
else
  run scenes/bench/room.xml room
  run "$big" big-4000
  compare "$mirrors" mirrors-2880
fi
