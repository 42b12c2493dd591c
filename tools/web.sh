#!/usr/bin/env bash
# The workbench in the browser: build it into a static folder, build and serve it locally, test it in
# headless Chromium, or measure it.
#
#   tools/web.sh build         → target/web/ (index.html, dualcal.js, dualcal_bg.wasm): host it anywhere
#   tools/web.sh serve [PORT]  → build, then serve target/web on http://127.0.0.1:PORT (default 8080)
#   tools/web.sh test          → build, then the browser test (web/tests/browser-test.mjs: Debian's
#                                Chromium headless, driven by playwright-core from npm), comparing the
#                                browser's calibrated parameters with the native command line's
#   tools/web.sh measure       → test, plus the native release command line's time for the same
#                                calibration, and the README's screenshot (docs/screenshot-web.png);
#                                prints the figures of docs/performance.md
#
# Needs the wasm32-unknown-unknown target (added here with rustup) and wasm-bindgen-cli at exactly the
# version of the `wasm-bindgen` crate in Cargo.lock, installed from crates.io into
# target/tools/wasm-bindgen-<version>/ the first time (a few minutes). The test needs node/npm and
# /usr/bin/chromium (tools/test installs Debian's `chromium`; CHROMIUM=path overrides).
set -euo pipefail
cd "$(dirname "$0")/.."

out=target/web
wasm=target/wasm32-unknown-unknown/release/dualcal.wasm
say() { printf 'tools/web.sh: %s\n' "$*" >&2; }

wasm_bindgen_version() {
  awk '$0 == "name = \"wasm-bindgen\"" { getline; gsub(/"/, "", $3); print $3; exit }' Cargo.lock
}

install_wasm_bindgen() {
  local version root
  version=$(wasm_bindgen_version)
  [ -n "$version" ] || { say "no wasm-bindgen in Cargo.lock"; exit 1; }
  root=target/tools/wasm-bindgen-$version
  if ! [ -x "$root/bin/wasm-bindgen" ]; then
    say "installing wasm-bindgen-cli $version into $root"
    # --locked reproduces the CLI's own lockfile; if the registry lacks one of its pinned versions,
    # resolve afresh (the same CLI version, its dependencies' newest compatible releases).
    cargo install wasm-bindgen-cli --version "=$version" --locked --root "$root" --quiet ||
      cargo install wasm-bindgen-cli --version "=$version" --root "$root" --quiet
  fi
  bindgen=$root/bin/wasm-bindgen
}

build() {
  local started=$SECONDS
  if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
    rustup target add wasm32-unknown-unknown
  fi
  install_wasm_bindgen
  cargo build --release --target wasm32-unknown-unknown --bin dualcal
  local tmp=$out.tmp
  rm -rf "$tmp"
  mkdir -p "$tmp"
  "$bindgen" --target web --no-typescript --out-dir "$tmp" --out-name dualcal "$wasm"
  if command -v wasm-opt >/dev/null 2>&1; then
    wasm-opt -O2 --enable-bulk-memory --enable-nontrapping-float-to-int --enable-sign-ext \
      --enable-mutable-globals --enable-reference-types \
      "$tmp/dualcal_bg.wasm" -o "$tmp/dualcal_bg.wasm"
  fi
  cp web/index.html "$tmp/"
  rm -rf "$out"
  mv "$tmp" "$out"
  local raw gz
  raw=$(stat -c %s "$out/dualcal_bg.wasm")
  gz=$(gzip -9 -c "$out/dualcal_bg.wasm" | wc -c)
  mkdir -p target/web-test
  printf '{"wasm_bytes": %s, "wasm_gzip_bytes": %s, "build_secs": %s}\n' "$raw" "$gz" \
    "$((SECONDS - started))" >target/web-test/build.json
  say "built $out in $((SECONDS - started)) s: dualcal_bg.wasm $((raw / 1024)) KiB ($((gz / 1024)) KiB gzip -9)"
}

browser_test() {
  local started=$SECONDS
  mkdir -p target/web-test
  # The native command line's parameters of the example, to compare with the browser's. The binary is
  # the one `cargo test` builds (its dependencies' features are the tests'; `cargo run` would build
  # them again without): up to date right after tools/test's `cargo test`.
  cargo test --quiet --no-run --test cli 2>/dev/null
  rm -f target/web-test/params-native.json
  target/debug/dualcal calibrate assets/datasets/example --quiet \
    --out target/web-test/params-native.json >target/web-test/calibrate-native.txt
  # The example as one .zip, for the drop test (written here, not committed).
  rm -f target/web-test/example.zip
  (cd assets/datasets && python3 -m zipfile -c ../../target/web-test/example.zip example)
  (cd web/tests && npm ci --no-audit --no-fund --silent)
  node web/tests/browser-test.mjs --native-params target/web-test/params-native.json "$@"
  say "browser test done in $((SECONDS - started)) s (after the build)"
}

case "${1:-}" in
  build)
    build
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
    ;;
  measure)
    build
    browser_test
    # The same calibration natively: the release command line's solver time (`total time`), five
    # runs. The engine alone (no workbench) is enough for that, and builds in a few minutes.
    cargo build --release --quiet --no-default-features --bin dualcal
    for i in 1 2 3 4 5; do
      rm -f "target/web-test/native-$i.json"
      target/release/dualcal calibrate assets/datasets/example --out "target/web-test/native-$i.json" |
        awk '/^total time/ { print $3 }'
    done >target/web-test/native-cli-secs.txt
    if command -v convert >/dev/null 2>&1; then
      convert target/web-test/workbench.png -colors 256 PNG8:docs/screenshot-web.png
    else
      cp target/web-test/workbench.png docs/screenshot-web.png
    fi
    node web/tests/report.mjs
    ;;
  *)
    say "usage: tools/web.sh build | serve [PORT] | test | measure"
    exit 2
    ;;
esac
