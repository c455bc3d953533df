#!/usr/bin/env bash
# The headless command line built for Windows, run under Wine, against the
# Linux binary of the same commit:
#
#   .ci/windows.sh LINUX_BINARY WINDOWS_EXE
#
# 1. renders of every golden and bench scene (and a few methods, formats
#    and thread counts) are byte-identical to the Linux binary's;
# 2. errors (a missing file, a bad attribute, malformed XML, an unknown
#    flag, an unknown format, a bad thread count) give the same exit status
#    and, but for the system's wording of an OS error, the same message;
# 3. `edit` changes a scene in place (the file renamed over while no
#    handle of ours holds it: Windows refuses that) and writes the same
#    bytes as on Linux, and `-out` beside it too;
# 4. split, --region and assemble give the whole render's file;
# 5. `lsp` answers an editor: capabilities, then a diagnostic for broken
#    text (the link to the app is Unix-only and left out here).
#
# Wine 8 (Debian bookworm) lacks bcryptprimitives.dll's ProcessPrng, which
# Rust's standard library calls: a stub (.ci/wine/bcryptprimitives.c,
# RtlGenRandom underneath) is built with mingw-w64 and put beside the
# .exe, for these tests only.
set -euo pipefail

linux=$(realpath "$1")
exe=$(realpath "$2")
here=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'wineserver -k >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
export WINEPREFIX=$work/prefix WINEDEBUG=-all WINEDLLOVERRIDES="mscoree,mshtml="

fail() { echo "windows: FAIL: $*" >&2; exit 1; }
say() { echo "windows: $*"; }

mkdir -p "$work/bin" "$work/run"
cp "$exe" "$work/bin/rayoflight.exe"
x86_64-w64-mingw32-gcc -O2 -shared -o "$work/bin/bcryptprimitives.dll" \
    "$here/.ci/wine/bcryptprimitives.c" "$here/.ci/wine/bcryptprimitives.def" -ladvapi32
# One server for the whole run: by default the server quits a few seconds
# after its last client, and a command that connects as it quits dies with
# "wine client error: recvmsg: Connection reset by peer" (a CI run did).
mkdir -p "$WINEPREFIX"
wineserver -p
wineboot -i >/dev/null 2>&1 || true
cd "$work/run"
win() { timeout 300 wine "$work/bin/rayoflight.exe" "$@"; }
lin() { timeout 300 "$linux" "$@"; }
say "$(win --version | tr -d '\r') under $(wine --version)"

# 1. Renders, byte for byte.
cp "$here"/scenes/golden/*.xml "$here"/scenes/bench/*.xml "$here"/scenes/example.xml .
count=0
for scene in *.xml; do
    lin --no-gui --quiet "$scene" -out "lin-${scene%.xml}.png"
    win --no-gui --quiet "$scene" -out "win-${scene%.xml}.png"
    cmp -s "lin-${scene%.xml}.png" "win-${scene%.xml}.png" || fail "$scene renders differently"
    count=$((count + 1))
done
say "$count scenes render byte-identical"
for args in "--method f32" "--method aa4" "--aa 3 --threads 1" "--threads 3" "--pass normal"; do
    for ext in png jpg exr; do
        # shellcheck disable=SC2086
        lin --no-gui --quiet mirror-spheres.xml $args -out "lin.$ext"
        # shellcheck disable=SC2086
        win --no-gui --quiet mirror-spheres.xml $args -out "win.$ext"
        cmp -s "lin.$ext" "win.$ext" || fail "mirror-spheres $args .$ext differs"
    done
done
say "methods, passes, thread counts and formats byte-identical (png, jpg, exr)"

# 2. Errors.
printf '<scene><sphere><color red="2"/></sphere></scene>' >bad.xml
printf '<scene><sphere>' >broken.xml
check_error() {
    local l w ls ws
    l=$(lin "$@" 2>&1 >/dev/null) && ls=0 || ls=$?
    w=$(win "$@" 2>&1 >/dev/null | tr -d '\r') && ws=0 || ws=$?
    [[ $ls == "$ws" && $ls != 0 ]] || fail "'$*': exit $ls on Linux, $ws on Windows"
    # An OS error is worded by the system; the rest is ours.
    [[ ${l%%: No such file*} == "${w%%: File not found*}" ]] || fail "'$*': '$l' against '$w'"
}
check_error --no-gui missing.xml
check_error --no-gui bad.xml
check_error --no-gui broken.xml
check_error --bogus
check_error --no-gui example.xml -out x.bmpx
check_error --no-gui example.xml --threads 0
check_error edit example.xml --set 'object[9].material.ka=0.5'
say "errors: same status and message"

# 3. edit, in place and beside.
cp example.xml lin-ed.xml
cp example.xml win-ed.xml
lin edit lin-ed.xml --set 'object[2].material.ka=0.5' --set 'camera.width=320'
win edit win-ed.xml --set 'object[2].material.ka=0.5' --set 'camera.width=320'
cmp -s lin-ed.xml win-ed.xml || fail "edit in place writes other bytes"
cmp -s lin-ed.xml example.xml && fail "edit in place changed nothing"
win edit example.xml --set 'object[1].material.kd=0.25' -out win-beside.xml
lin edit example.xml --set 'object[1].material.kd=0.25' -out lin-beside.xml
cmp -s lin-beside.xml win-beside.xml || fail "edit -out writes other bytes"
say "edit in place and -out: same bytes as on Linux"

# 4. split, --region, assemble.
lin --no-gui --quiet mirror-spheres.xml --aa 2 -out whole.png
parts=()
n=0
while read -r region; do
    region=${region%$'\r'}
    win --no-gui --quiet mirror-spheres.xml --aa 2 --region "$region" -out "part-$n.png"
    parts+=("part-$n.png")
    n=$((n + 1))
done < <(win split mirror-spheres.xml --tasks 5)
[[ $n == 5 ]] || fail "split gave $n regions, not 5"
win assemble -out assembled.png "${parts[@]}"
cmp -s whole.png assembled.png || fail "the assembled image differs from the whole render"
say "split into 5, rendered by region, assembled: the whole render's file"

# 5. lsp: capabilities, then a diagnostic for broken text.
message() { printf 'Content-Length: %d\r\n\r\n%s' "${#1}" "$1"; }
{
    message '{"jsonrpc":"2.0","id":1,"method":"initialize","params":{"capabilities":{}}}'
    message '{"jsonrpc":"2.0","method":"initialized","params":{}}'
    message '{"jsonrpc":"2.0","method":"textDocument/didOpen","params":{"textDocument":{"uri":"file:///C:/scenes/s.xml","languageId":"xml","version":1,"text":"<scene><sphere>"}}}'
    sleep 3
    message '{"jsonrpc":"2.0","id":2,"method":"shutdown"}'
    message '{"jsonrpc":"2.0","method":"exit"}'
} | win lsp >lsp.out
grep -q '"capabilities"' lsp.out || fail "lsp: no capabilities: $(head -c 400 lsp.out)"
grep -q '"textDocument/publishDiagnostics"' lsp.out && grep -q 'is not closed' lsp.out ||
    fail "lsp: no diagnostic for broken text: $(head -c 800 lsp.out)"
say "lsp: capabilities and a diagnostic"

say "passed"
