#!/usr/bin/env bash
# Regenerates the golden reference images tests/golden/<name>.png from
# scenes/golden/<name>.xml with POV-Ray 3.7, through our exporter
# (`rayoflight export-pov`; docs/scene-format.md, Cross-checking with POV-Ray):
#
#   povray -A +FN File_Gamma=1.0 +W<w> +H<h> +I<name>.pov +O<name>.png
#
# Usage: tests/golden/regenerate.sh [name ...]   (default: every golden scene)
# Needs povray 3.7 on PATH (Debian/Ubuntu: apt-get install povray).
# The references are POV-Ray's pictures, not ours: never regenerate them with
# our renderer, and review the new images before committing them.
set -euo pipefail

root="$(cd "$(dirname "$0")/../.." && pwd)"
cd "$root"

if ! command -v povray >/dev/null 2>&1; then
    echo "regenerate.sh: povray is not on PATH (apt-get install povray)" >&2
    exit 1
fi
if ! povray --version 2>&1 | grep -q "POV-Ray 3\.7"; then
    echo "regenerate.sh: POV-Ray 3.7 is required; found:" >&2
    povray --version 2>&1 | grep "POV-Ray" >&2 || true
    exit 1
fi

cargo build --release --no-default-features
target_dir="${CARGO_TARGET_DIR:-$root/target}"
case "$target_dir" in /*) ;; *) target_dir="$root/$target_dir" ;; esac
bin="$target_dir/release/rayoflight"

if [ "$#" -gt 0 ]; then
    scenes=()
    for name in "$@"; do scenes+=("scenes/golden/${name%.xml}.xml"); done
else
    scenes=(scenes/golden/*.xml)
fi

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# POV-Ray warns when it has no user configuration; give it an empty one.
export HOME="$tmp/home"
mkdir -p "$HOME/.povray/3.7"
: > "$HOME/.povray/3.7/povray.conf"

strip_dates() {
    if command -v python3 >/dev/null 2>&1; then
        python3 - "$1" "$2" <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read()
out, i = [data[:8]], 8
while i < len(data):
    n = struct.unpack(">I", data[i:i + 4])[0]
    if data[i + 4:i + 8] not in (b"tIME", b"tEXt"):
        out.append(data[i:i + 12 + n])
    i += 12 + n
open(sys.argv[2], "wb").write(b"".join(out))
PY
    else
        cp "$1" "$2"
    fi
}

for scene in "${scenes[@]}"; do
    name="$(basename "$scene" .xml)"
    "$bin" export-pov "$scene" -out "$tmp/$name.pov"
    # The exporter's header names the size: "// Render: povray ... +W<w> +H<h> ...".
    size="$(grep -m1 -o '+W[0-9]* +H[0-9]*' "$tmp/$name.pov")"
    # Run from the temporary directory: POV-Ray's default I/O restrictions
    # only allow writing below the current directory.
    # shellcheck disable=SC2086
    if ! (cd "$tmp" && povray -D -A +FN File_Gamma=1.0 $size \
        "+I$name.pov" "+O$name.png" > "$name.log" 2>&1); then
        cat "$tmp/$name.log" >&2
        echo "regenerate.sh: povray failed on $scene" >&2
        exit 1
    fi
    # Drop the render date (tIME, tEXt) so that an unchanged picture gives an
    # unchanged file; the pixels are POV-Ray's, untouched.
    strip_dates "$tmp/$name.png" "tests/golden/$name.png"
    trace="$(grep -m1 'Trace Time:' "$tmp/$name.log" | sed 's/.*(\(.*\))/\1/' || true)"
    printf '%-22s %-12s trace %s\n' "$name" "$size" "${trace:-?}"
done
