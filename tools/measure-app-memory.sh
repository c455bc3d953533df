#!/usr/bin/env bash
# The app on a big scene, as a user meets it: how soon its window maps,
# when its first picture is done, and its peak memory (VmHWM) after that
# picture, after an edit and after a save. Under Xvfb; the edit is a drag
# on the ka field of the first object (selected first) in the panel, at
# the panel's default layout on a 1280x900 screen; the save is Ctrl+S.
# The scene is copied first: the original is never written. Prints the
# figures, and how many bytes of the saved copy differ from the original
# (1: the one digit of ka the edit changed).
#
#   tools/measure-app-memory.sh target/release/rayoflight SCENE
#
# The picture is taken as done when the process has stayed idle for half
# a second after working (its CPU time unchanged). Needs Xvfb, xdotool,
# imagemagick (import, for a look at the screen: saved under $OUT or /tmp).
set -u
bin=$(realpath "$1")
scene=$2
out=${OUT:-/tmp}
work=$(mktemp -d)
display=:$((RANDOM % 100 + 400))
cp "$scene" "$work/scene.xml"
Xvfb "$display" -screen 0 1280x900x24 -nolisten tcp >/dev/null 2>&1 &
xvfb=$!
trap 'kill $xvfb $pid 2>/dev/null; rm -rf "$work"' EXIT
sleep 1
export DISPLAY=$display LIBGL_ALWAYS_SOFTWARE=1 XDG_CONFIG_HOME=$work/cfg \
    XDG_STATE_HOME=$work/state XDG_RUNTIME_DIR=$work/run
mkdir -m 700 "$work/run"
start=$(date +%s%N)
ms() { echo $((($(date +%s%N) - start) / 1000000)); }
"$bin" "$work/scene.xml" >/dev/null 2>&1 &
pid=$!
win=$(xdotool search --sync --onlyvisible --pid $pid 2>/dev/null | head -1)
echo "window mapped after $(ms) ms"
cpu() { awk '{print $14 + $15}' /proc/$pid/stat; }
peak() { awk '/VmHWM/ {printf "%.0f MB", $2 / 1000}' /proc/$pid/status; }
last=$(cpu) idle=0 worked=0
until [ $worked = 1 ] && [ $idle -ge 5 ]; do
    sleep 0.1
    now=$(cpu)
    if [ "$now" = "$last" ]; then idle=$((idle + 1)); else idle=0 worked=1; fi
    last=$now
done
echo "the picture done (idle) after $(($(ms) - 500)) ms; peak $(peak)"
import -window root "$out/app-picture.png" 2>/dev/null
xdotool windowfocus --sync "$win" 2>/dev/null
xdotool mousemove --window "$win" 50 286 click 1 2>/dev/null
sleep 1
xdotool mousemove --window "$win" 93 612 mousedown 1 2>/dev/null
for x in 103 113 123; do sleep 0.2; xdotool mousemove --window "$win" $x 612 2>/dev/null; done
xdotool mouseup 1 2>/dev/null
sleep 8
echo "after an edit: peak $(peak)"
import -window root "$out/app-edited.png" 2>/dev/null
xdotool key --window "$win" ctrl+s 2>/dev/null
sleep 8
echo "after a save: peak $(peak)"
import -window root "$out/app-saved.png" 2>/dev/null
echo "$(cmp -l "$scene" "$work/scene.xml" | wc -l) bytes of the saved copy differ from the original"
