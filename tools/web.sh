#!/usr/bin/env bash
# The workbench in the browser: build it into a static folder, build and serve it locally, test it in
# headless Chromium, or measure it.
#
#   tools/web.sh build         → target/web/ (index.html, dualcal.js, dualcal_bg.wasm): host it anywhere
#   tools/web.sh build-webgpu  → target/web-webgpu/: the experimental WebGPU-only module (smaller; needs a
#                                browser with a WebGPU adapter; not the default, docs/performance.md)
#   tools/web.sh serve [PORT]  → build, then serve target/web on http://127.0.0.1:PORT (default 8080)
#   tools/web.sh test          → build, then the browser test (web/tests/browser-test.mjs: Debian's
#                                Chromium headless, driven by playwright-core from npm), comparing the
#                                browser's calibrated parameters with the native command line's;
#                                then the calibration report of the same parameters
#                                (web/tests/report-test.mjs: every section, no console error)
#   tools/web.sh measure       → test, plus the native release command line's time for the same
#                                calibration, and the README's screenshot (docs/screenshot-web.png);
#                                prints the figures of docs/performance.md
#
# Needs the wasm32-unknown-unknown target (added here with rustup), wasm-bindgen-cli at exactly the
# version of the `wasm-bindgen` crate in Cargo.lock, installed from crates.io into
# <target>/tools/wasm-bindgen-<version>/ the first time (a few minutes), and Node.js/npm: the build
# optimises the module for size with binaryen's wasm-opt at the version pinned in
# web/tests/package-lock.json (never whatever wasm-opt the machine has: an old one, such as Debian 12's
# binaryen 108, writes a module whose reference-type table the browser refuses at start-up). The test
# needs /usr/bin/chromium (tools/test installs Debian's `chromium`; CHROMIUM=path overrides).
# DUALCAL_WASM_OPT=0 skips wasm-opt (a faster build, a larger module).
set -euo pipefail
cd "$(dirname "$0")/.."

say() { printf 'tools/web.sh: %s\n' "$*" >&2; }
# Cargo's target directory (CARGO_TARGET_DIR or the workspace's target/).
target_dir=$(cargo metadata --format-version 1 --no-deps |
  python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
out=$target_dir/web
wasm=$target_dir/wasm32-unknown-unknown/wasm-release/dualcal.wasm
test_out=$target_dir/web-test
export DUALCAL_WEB_SITE=$out DUALCAL_WEB_TEST_OUT=$test_out

wasm_bindgen_version() {
  awk '$0 == "name = \"wasm-bindgen\"" { getline; gsub(/"/, "", $3); print $3; exit }' Cargo.lock
}

install_wasm_bindgen() {
  local version root
  version=$(wasm_bindgen_version)
  [ -n "$version" ] || { say "no wasm-bindgen in Cargo.lock"; exit 1; }
  root=$target_dir/tools/wasm-bindgen-$version
  if ! [ -x "$root/bin/wasm-bindgen" ]; then
    say "installing wasm-bindgen-cli $version into $root"
    # Not --locked: the CLI's own lockfile pins releases the registry no longer serves (webpki-roots
    # 1.0.11 in 0.2.130's). The CLI's version is exact; its dependencies resolve to their newest
    # compatible releases. Errors stay visible.
    cargo install wasm-bindgen-cli --version "=$version" --root "$root"
  fi
  bindgen=$root/bin/wasm-bindgen
}

# web/tests' npm packages (playwright-core, binaryen), at the versions of its package-lock.json.
npm_ci() {
  if ! command -v npm >/dev/null 2>&1; then
    say "npm not found: the browser build and test need Node.js 18+ and npm (tools/test installs them on Debian)"
    exit 2
  fi
  if ! [ -f web/tests/node_modules/.package-lock.json ] ||
    ! cmp -s web/tests/package-lock.json web/tests/node_modules/.dualcal-lock; then
    (cd web/tests && npm ci --no-audit --no-fund --silent)
    cp web/tests/package-lock.json web/tests/node_modules/.dualcal-lock
  fi
}

# build [FEATURES [OUT [BUILD_JSON]]]: the site with the module of Cargo features FEATURES (default
# `web`, WebGL2) in OUT (default target/web), its sizes in BUILD_JSON (default target/web-test/build.json).
build() {
  local features=${1:-web} out=${2:-$out} build_json=${3:-$test_out/build.json}
  local started=$SECONDS
  if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
    rustup target add wasm32-unknown-unknown
  fi
  install_wasm_bindgen
  # Optimised for size (Cargo.toml's wasm-release profile), with egui's fonts subset (`web-fonts`).
  # The source paths in panic messages without the machine's cargo registry and checkout (shorter,
  # and nothing of this machine's in the module). RUSTFLAGS replaces .cargo/config.toml's flags: SIMD
  # is named again.
  local flags="-C target-feature=+simd128 --remap-path-prefix=$PWD/=" registry
  for registry in "${CARGO_HOME:-$HOME/.cargo}"/registry/src/*/; do
    flags="$flags --remap-path-prefix=$registry="
  done
  RUSTFLAGS=$flags cargo build --profile wasm-release --target wasm32-unknown-unknown --bin dualcal \
    --features "$features"
  local tmp=$out.tmp
  rm -rf "$tmp"
  mkdir -p "$tmp"
  "$bindgen" --target web --no-typescript --out-dir "$tmp" --out-name dualcal "$wasm"
  local bindgen_bytes opt_secs=0
  bindgen_bytes=$(stat -c %s "$tmp/dualcal_bg.wasm")
  if [ "${DUALCAL_WASM_OPT:-1}" != 0 ]; then
    npm_ci
    local opt_started=$SECONDS
    # The features rustc's wasm32 target enables by default (reference types: wasm-bindgen's
    # externref table) and SIMD (.cargo/config.toml), so that wasm-opt keeps them as they are.
    web/tests/node_modules/.bin/wasm-opt -Oz --enable-bulk-memory --enable-nontrapping-float-to-int \
      --enable-sign-ext --enable-mutable-globals --enable-reference-types --enable-multivalue \
      --enable-simd \
      "$tmp/dualcal_bg.wasm" -o "$tmp/dualcal_bg.opt.wasm"
    mv "$tmp/dualcal_bg.opt.wasm" "$tmp/dualcal_bg.wasm"
    opt_secs=$((SECONDS - opt_started))
  fi
  cp web/index.html "$tmp/"
  rm -rf "$out"
  mv "$tmp" "$out"
  local raw gz
  raw=$(stat -c %s "$out/dualcal_bg.wasm")
  gz=$(gzip -9 -c "$out/dualcal_bg.wasm" | wc -c)
  mkdir -p "$(dirname "$build_json")"
  printf '{"features": "%s", "wasm_bytes": %s, "wasm_gzip_bytes": %s, "wasm_bindgen_bytes": %s, "wasm_opt_secs": %s, "build_secs": %s}\n' \
    "$features" "$raw" "$gz" "$bindgen_bytes" "$opt_secs" "$((SECONDS - started))" >"$build_json"
  say "built $out in $((SECONDS - started)) s (wasm-opt $opt_secs s): dualcal_bg.wasm $((raw / 1024)) KiB ($((gz / 1024)) KiB gzip -9; $((bindgen_bytes / 1024)) KiB before wasm-opt)"
}

browser_test() {
  local started=$SECONDS
  mkdir -p "$test_out"
  # The native command line's parameters of the example, to compare with the browser's. The binary is
  # the one `cargo test` builds (its dependencies' features are the tests'; `cargo run` would build
  # them again without): up to date right after tools/test's `cargo test`.
  cargo test --quiet --no-run --test cli
  rm -f "$test_out/params-native.json"
  "$target_dir/debug/dualcal" calibrate assets/datasets/example --quiet \
    --out "$test_out/params-native.json" >"$test_out/calibrate-native.txt"
  # The example as one .zip, for the drop test (written here, not committed).
  rm -f "$test_out/example.zip"
  python3 -m zipfile -c "$test_out/example.zip" assets/datasets/example
  npm_ci
  node web/tests/browser-test.mjs --native-params "$test_out/params-native.json" "$@"
  say "browser test done in $((SECONDS - started)) s (after the build)"
}

# The calibration report (`dualcal report`) of the native parameters in the browser: every section
# visible, no console error, a screenshot (target/web-test/report.png). After browser_test, whose
# binary and parameters it uses.
report_test() {
  "$target_dir/debug/dualcal" report assets/datasets/example --params "$test_out/params-native.json" \
    --out "$test_out/report.html"
  node web/tests/report-test.mjs "$test_out/report.html"
}

case "${1:-}" in
  build)
    build
    ;;
  build-webgpu)
    # Experimental: the module on wgpu's WebGPU backend alone (feature `web-webgpu`), in
    # target/web-webgpu/ (sizes in target/web-test/build-webgpu.json); it starts only in a browser
    # with a WebGPU adapter. Not the default: docs/performance.md, "Size, fourteenth session".
    build web-webgpu "$target_dir/web-webgpu" "$test_out/build-webgpu.json"
    ;;
  serve)
    build
    port=${2:-8080}
    say "serving $out on http://127.0.0.1:$port/ (Ctrl-C stops)"
    exec python3 -m http.server "$port" --bind 127.0.0.1 --directory "$out"
    ;;
  test)
    build
    browser_test
    report_test
    ;;
  measure)
    build
    browser_test
    # The same calibration natively: the release command line's solver time (`total time`), five
    # runs. The engine alone (no workbench) is enough for that, and builds in a few minutes.
    cargo build --release --quiet --no-default-features --bin dualcal
    for i in 1 2 3 4 5; do
      rm -f "$test_out/native-$i.json"
      "$target_dir/release/dualcal" calibrate assets/datasets/example --out "$test_out/native-$i.json" |
        awk '/^total time/ { print $3 }'
    done >"$test_out/native-cli-secs.txt"
    if convert -version >/dev/null 2>&1; then
      convert "$test_out/workbench.png" -colors 256 PNG8:docs/screenshot-web.png
    else
      cp "$test_out/workbench.png" docs/screenshot-web.png
    fi
    node web/tests/report.mjs
    ;;
  *)
    say "usage: tools/web.sh build | build-webgpu | serve [PORT] | test | measure"
    exit 2
    ;;
esac
