#!/usr/bin/env bash
# The web demo: the `web` example built for wasm32-unknown-unknown (WebGL2, one
# thread), bound to JavaScript by wasm-bindgen and written with its page into a static
# folder that any web server serves. Installs what a fresh machine lacks: the wasm32
# target (rustup), wasm-bindgen-cli at the version Cargo.lock pins (from crates.io,
# built here) and Binaryen's wasm-opt (from the npm registry, into target/binaryen).
#
# Usage: scripts/web.sh [output folder, default target/web-demo]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-target/web-demo}

rustup target list --installed | grep -qx wasm32-unknown-unknown \
    || rustup target add wasm32-unknown-unknown
# The command-line tool must be the same version as the wasm-bindgen crate linked in.
version=$(awk '$0 == "name = \"wasm-bindgen\"" { getline; gsub(/"/, "", $3); print $3; exit }' Cargo.lock)
if [ "$(wasm-bindgen --version 2>/dev/null | awk '{ print $2 }')" != "$version" ]; then
    # Its own lock file pins crates a registry may no longer offer (a yanked
    # webpki-roots, seen here): then resolve afresh within its version requirements.
    cargo install wasm-bindgen-cli --version "$version" --locked \
        || cargo install wasm-bindgen-cli --version "$version"
fi

CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUSTFLAGS="-C target-feature=+simd128" \
    cargo build --profile web --target wasm32-unknown-unknown -p bevy_strands_app \
    --features web --example web
mkdir -p "$out"
wasm-bindgen --target web --no-typescript --remove-name-section --remove-producers-section --out-dir "$out" --out-name strands \
    target/wasm32-unknown-unknown/web/examples/web.wasm
cp app/web/index.html "$out/"
wasm="$out/strands_bg.wasm"

# Binaryen's size optimizer takes a sixth off the wasm (three minutes of one core). The
# features are those rustc's wasm32 target emits, with the simd128 asked for above.
binaryen=132.0.0
wasm_opt=target/binaryen/node_modules/.bin/wasm-opt
if [ ! -x "$wasm_opt" ] || [ "$("$wasm_opt" --version | awk '{ print $3 }')" != "${binaryen%%.*}" ]; then
    if command -v npm >/dev/null 2>&1; then
        npm install --silent --no-audit --no-fund --prefix target/binaryen "binaryen@$binaryen"
    else
        echo "npm is missing: the page's wasm is not run through wasm-opt"
    fi
fi
if [ -x "$wasm_opt" ]; then
    echo "before wasm-opt: $(wc -c < "$wasm") bytes, $(gzip -9 -c "$wasm" | wc -c) gzipped"
    "$wasm_opt" -Oz --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext \
        --enable-mutable-globals --enable-reference-types --enable-multivalue --enable-simd \
        "$wasm" -o "$wasm.opt"
    mv "$wasm.opt" "$wasm"
fi
echo "the page's wasm: $(wc -c < "$wasm") bytes, $(gzip -9 -c "$wasm" | wc -c) gzipped"
echo "the web demo is in $out: serve it, e.g. python3 -m http.server -d $out 8080,"
echo "and open http://localhost:8080 (?scene=meatball_factory or ?scene=long_strand)"
