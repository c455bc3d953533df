#!/usr/bin/env bash
# Time from a keystroke in the editor to the picture in the app: the app
# under Xvfb on SCENE, Neovim (headless, with `rayoflight lsp`) changing
# the first light's x without saving, screenshots taken as fast as
# ImageMagick's import goes until the picture differs. Prints one line per
# change: the milliseconds from the change to the first screenshot that
# shows it (the screenshot's own cost, ~50-100 ms, included), looking at
# the picture's side of a 1280x900 screen only.
#
#   tools/measure-follow.sh target/release/rayoflight SCENE [CHANGES]
#
# Needs Xvfb, xdotool, imagemagick, neovim, python3.
set -euo pipefail
bin=$(realpath "$1")
scene=$2
changes=${3:-5}
work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT
cp "$scene" "$work/scene.xml"
mkdir -m 700 "$work/run"
display=:$((RANDOM % 100 + 300))
Xvfb "$display" -screen 0 1280x900x24 -nolisten tcp >/dev/null 2>&1 &
sleep 1
export DISPLAY=$display XDG_RUNTIME_DIR=$work/run LIBGL_ALWAYS_SOFTWARE=1
XDG_CONFIG_HOME=$work/cfg XDG_STATE_HOME=$work/state "$bin" "$work/scene.xml" >/dev/null 2>&1 &
for _ in $(seq 100); do ls "$work/run/rayoflight/"app-*.sock >/dev/null 2>&1 && break; sleep 0.1; done
sleep 3 # the first picture

line=$(grep -n '<light ' "$work/scene.xml" | head -1 | cut -d: -f1)
cat > "$work/changes.lua" <<EOF
local id = vim.lsp.start_client({ name = 'rayoflight', cmd = { '$bin', 'lsp' }, root_dir = '$work' })
vim.cmd('edit $work/scene.xml')
local buf = vim.api.nvim_get_current_buf()
vim.lsp.buf_attach_client(buf, id)
vim.wait(10000, function() local c = vim.lsp.get_client_by_id(id); return c ~= nil and c.initialized == true end, 20)
local row = $line - 1
local base = vim.api.nvim_buf_get_lines(buf, row, row + 1, false)[1]
for k = 1, $changes do
  vim.wait(3000, function() return false end, 50)
  local text = base:gsub('x="[^"]*"', 'x="' .. (k % 2 == 1 and 7 or -7) .. '"', 1)
  local f = io.open('$work/changed', 'w'); f:write(string.format('%.6f', vim.loop.hrtime() / 1e9)); f:close()
  vim.api.nvim_buf_set_lines(buf, row, row + 1, false, { text })
end
vim.wait(3000, function() return false end, 50)
vim.cmd('qa!')
EOF

python3 - "$work" "$changes" <<'EOF' &
import os, subprocess, sys, time
work, changes = sys.argv[1], int(sys.argv[2])
def shot():
    # The picture's side of the window only: the status bar changes too.
    return subprocess.run(
        ["import", "-window", "root", "-crop", "860x700+330+40", "rgb:-"],
        capture_output=True,
    ).stdout
def clock():
    return time.clock_gettime(time.CLOCK_MONOTONIC)
seen = None
base = shot()
done = 0
while done < changes:
    try:
        stamp = open(os.path.join(work, "changed")).read()
    except OSError:
        time.sleep(0.01)
        continue
    if stamp == seen or not stamp:
        base = shot()
        continue
    seen, at = stamp, float(stamp)
    while shot() == base:
        if clock() - at > 10:
            print("no change on screen after 10 s")
            break
    print(f"keystroke to picture: {(clock() - at) * 1000:.0f} ms")
    done += 1
    time.sleep(0.5)
    base = shot()
EOF
watcher=$!
nvim --headless --clean -u NONE -S "$work/changes.lua"
wait "$watcher"
