#!/usr/bin/env bash
# Builds a Debian package of RayOfLight with cargo-deb (`cargo install
# cargo-deb`): the binary, the desktop entry, the icons, the MIME type, the
# AppStream metadata, and the man pages and shell completions, which are
# generated here from the built binary (they come from the same clap
# definition as --help) into target/assets/, where [package.metadata.deb]
# in Cargo.toml looks for them.
set -euo pipefail
cd "$(dirname "$0")/.."

cargo build --release --locked
bin=target/release/rayoflight
out=target/assets
rm -rf "$out"
mkdir -p "$out/man" "$out/completions"

"$bin" man --dir "$out/man"
gzip -9n "$out/man"/*.1
"$bin" completions bash > "$out/completions/rayoflight"
"$bin" completions zsh > "$out/completions/_rayoflight"
"$bin" completions fish > "$out/completions/rayoflight.fish"

# --strip: the release profile keeps line tables for backtraces here; the
# package leaves them out (156 MB installed without it, 24 MB with it).
cargo deb --no-build --strip "$@"
