#!/bin/sh
# Builds the tsfc playground (docs/playground.md) into a folder of static
# files: index.html, app.js, worker.js, tsfc.js, style.css and
# tsfc_playground.wasm. Usage: playground/build.sh [OUT] (default
# target/playground). Needs the wasm32-wasip1 target:
#   rustup target add wasm32-wasip1
# Serve the folder (a file:// page cannot start a worker), e.g.:
#   python3 -m http.server -d target/playground 8000
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-"$root/target/playground"}
if ! rustup target list --installed 2>/dev/null | grep -qx wasm32-wasip1; then
    echo "error: the wasm32-wasip1 target is not installed (rustup target add wasm32-wasip1)" >&2
    exit 2
fi
cd "$root"
cargo build --release --locked -p tsfc-playground --target wasm32-wasip1
mkdir -p "$out"
for f in index.html app.js worker.js tsfc.js style.css; do
    cp "playground/web/$f" "$out/$f.tmp" && mv "$out/$f.tmp" "$out/$f"
done
wasm="${CARGO_TARGET_DIR:-$root/target}/wasm32-wasip1/release/tsfc_playground.wasm"
cp "$wasm" "$out/tsfc_playground.wasm.tmp" && mv "$out/tsfc_playground.wasm.tmp" "$out/tsfc_playground.wasm"
echo "built the playground in $out ($(wc -c <"$out/tsfc_playground.wasm") bytes of wasm); serve it with: python3 -m http.server -d $out 8000"
