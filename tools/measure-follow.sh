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
# PAUSE (seconds, default 3) is the time between changes, and before the
# first; a big scene needs more (the app reads the editor's first text
# whole). The first change is the one that hands the app the whole text.
#
# SAVE=1 (raw client only): after the first change the client writes the
# text to the file and says so (`didSave`), so the second change is the
# first after a save.
#
# EDITOR=raw puts a raw client (python, the protocol's messages written
# by hand) in Neovim's place: the time from the change sent to the server
# to the picture, without the editor's own cost (Neovim 0.7's client does
# work that grows with the buffer at each change: most of a keystroke on
# a million spheres).
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
pause=${PAUSE:-3}
sleep "$pause" # the first picture

line=$(grep -n '<light ' "$work/scene.xml" | head -1 | cut -d: -f1)
cat > "$work/changes.lua" <<EOF
local id = vim.lsp.start_client({ name = 'rayoflight', cmd = { '$bin', 'lsp' }, root_dir = '$work' })
vim.cmd('edit $work/scene.xml')
local buf = vim.api.nvim_get_current_buf()
vim.lsp.buf_attach_client(buf, id)
vim.wait(60000, function() local c = vim.lsp.get_client_by_id(id); return c ~= nil and c.initialized == true end, 20)
local row = $line - 1
local base = vim.api.nvim_buf_get_lines(buf, row, row + 1, false)[1]
for k = 1, $changes do
  vim.wait($pause * 1000, function() return false end, 50)
  local text = base:gsub('x="[^"]*"', 'x="' .. (k % 2 == 1 and 7 or -7) .. '"', 1)
  local f = io.open('$work/changed', 'w'); f:write(string.format('%.6f', vim.loop.hrtime() / 1e9)); f:close()
  vim.api.nvim_buf_set_lines(buf, row, row + 1, false, { text })
end
vim.wait($pause * 1000, function() return false end, 50)
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
        if clock() - at > 60:
            print("no change on screen after 60 s")
            break
    print(f"keystroke to picture: {(clock() - at) * 1000:.0f} ms")
    done += 1
    time.sleep(0.5)
    base = shot()
EOF
watcher=$!
if [ "${EDITOR:-}" = raw ]; then
  python3 - "$bin" "$work/scene.xml" "$line" "$changes" "$pause" "$work/changed" "${SAVE:-}" <<'RAW'
import json, re, subprocess, sys, time
binary, scene, line, changes, pause, stamp, save = sys.argv[1:8]
row, changes, pause = int(line) - 1, int(changes), float(pause)
text = open(scene).read()
server = subprocess.Popen([binary, "lsp"], stdin=subprocess.PIPE, stdout=subprocess.DEVNULL)
def send(message):
    body = json.dumps(dict(message, jsonrpc="2.0")).encode()
    server.stdin.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)
    server.stdin.flush()
send({"id": 0, "method": "initialize", "params": {"capabilities": {}}})
send({"method": "initialized", "params": {}})
uri = "file://" + scene
send({"method": "textDocument/didOpen", "params": {"textDocument": {
    "uri": uri, "languageId": "xml", "version": 1, "text": text}}})
base = text.split("\n")[row]
value = re.search(r'x="([^"]*)"', base)
start, old = value.start(1), value.group(1)
for k in range(1, changes + 1):
    time.sleep(pause)
    new = "7" if k % 2 == 1 else "-7"
    with open(stamp, "w") as f:
        f.write("%.6f" % time.clock_gettime(time.CLOCK_MONOTONIC))
    send({"method": "textDocument/didChange", "params": {
        "textDocument": {"uri": uri, "version": k + 1},
        "contentChanges": [{"range": {
            "start": {"line": row, "character": start},
            "end": {"line": row, "character": start + len(old)}}, "text": new}]}})
    lines = text.split("\n")
    lines[row] = lines[row][:start] + new + lines[row][start + len(old):]
    text = "\n".join(lines)
    old = new
    if save and k == 1:
        time.sleep(pause)
        with open(scene, "w") as f:
            f.write(text)
        send({"method": "textDocument/didSave", "params": {"textDocument": {"uri": uri}}})
time.sleep(pause)
server.kill()
RAW
else
  nvim --headless --clean -u NONE -S "$work/changes.lua"
fi
wait "$watcher"
