#!/usr/bin/env bash
# The workbench in the browser: build it into a static folder, build and serve it locally, test it in
# headless Chromium, or measure it.
#
#   tools/web.sh build         → target/web/: index.html and the workbench built twice, on two of
#                                wgpu's backends — dualcal_webgpu.js + dualcal_webgpu_bg.wasm (the
#                                browser's WebGPU: the smaller module) and dualcal.js + dualcal_bg.wasm
#                                (WebGL2); the page loads the first where the browser has a hardware
#                                WebGPU adapter, else the second. Host the folder anywhere.
#   tools/web.sh serve [PORT]  → build, then serve target/web on http://127.0.0.1:PORT (default 8080)
#   tools/web.sh test          → build, then the browser test (web/tests/browser-test.mjs: Debian's
#                                Chromium headless, driven by playwright-core from npm) on each
#                                module, comparing the browser's calibrated parameters with the native
#                                command line's; then the calibration report of the same parameters
#                                (web/tests/report-test.mjs: every section, no console error)
#   tools/web.sh first-frame [N] → the time to the first frame over N fresh page loads per module
#                                (default 7; web/tests/first-frame.mjs): median, range, where it goes;
#                                on the site as last built
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
# A failure inside $(…) (a module's build) stops the script too.
shopt -s inherit_errexit
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

# The site in target/web: both modules and the page; their sizes in target/web-test/build.json.
build() {
  local started=$SECONDS
  if ! rustup target list --installed | grep -qx wasm32-unknown-unknown; then
    rustup target add wasm32-unknown-unknown
  fi
  install_wasm_bindgen
  local tmp=$out.tmp
  rm -rf "$tmp"
  mkdir -p "$tmp" "$test_out"
  # The Cargo feature of each module (Cargo.toml): `web-webgpu` and `web` (WebGL2).
  local modules_json
  modules_json=$(build_module web-webgpu webgpu dualcal_webgpu "$tmp")
  modules_json="$modules_json, $(build_module web webgl2 dualcal "$tmp")"
  cp web/index.html "$tmp/"
  rm -rf "$out"
  mv "$tmp" "$out"
  printf '{"modules": [%s], "build_secs": %s}\n' "$modules_json" "$((SECONDS - started))" >"$test_out/build.json"
  say "built $out in $((SECONDS - started)) s"
}

# build_module FEATURES BACKEND NAME DIR: the workbench with Cargo features FEATURES, out of
# wasm-bindgen as DIR/NAME.js and DIR/NAME_bg.wasm, optimised by wasm-opt; prints its sizes as JSON.
build_module() {
  local features=$1 backend=$2 name=$3 tmp=$4
  local started=$SECONDS
  # Optimised for size (Cargo.toml's wasm-release profile), with egui's fonts subset (`web-fonts`).
  # The source paths in panic messages without the machine's cargo registry and checkout (shorter,
  # and nothing of this machine's in the module). RUSTFLAGS replaces .cargo/config.toml's flags: SIMD
  # is named again.
  local flags="-C target-feature=+simd128 --remap-path-prefix=$PWD/=" registry
  for registry in "${CARGO_HOME:-$HOME/.cargo}"/registry/src/*/; do
    flags="$flags --remap-path-prefix=$registry="
  done
  # Cargo's output goes to stderr: this function's stdout is its JSON.
  RUSTFLAGS=$flags cargo build --profile wasm-release --target wasm32-unknown-unknown --bin dualcal \
    --features "$features" >&2
  "$bindgen" --target web --no-typescript --out-dir "$tmp" --out-name "$name" "$wasm" >&2
  local module=$tmp/${name}_bg.wasm bindgen_bytes opt_secs=0
  bindgen_bytes=$(stat -c %s "$module")
  if [ "${DUALCAL_WASM_OPT:-1}" != 0 ]; then
    npm_ci >&2
    local opt_started=$SECONDS
    # The features rustc's wasm32 target enables by default (reference types: wasm-bindgen's
    # externref table) and SIMD (.cargo/config.toml), so that wasm-opt keeps them as they are.
    web/tests/node_modules/.bin/wasm-opt -Oz --enable-bulk-memory --enable-nontrapping-float-to-int \
      --enable-sign-ext --enable-mutable-globals --enable-reference-types --enable-multivalue \
      --enable-simd \
      "$module" -o "$module.opt" >&2
    mv "$module.opt" "$module"
    opt_secs=$((SECONDS - opt_started))
  fi
  local raw gz
  raw=$(stat -c %s "$module")
  gz=$(gzip -9 -c "$module" | wc -c)
  say "$backend module ${name}_bg.wasm in $((SECONDS - started)) s (wasm-opt $opt_secs s): $((raw / 1024)) KiB, $((gz / 1024)) KiB gzip -9 ($((bindgen_bytes / 1024)) KiB before wasm-opt)"
  printf '{"backend": "%s", "features": "%s", "file": "%s", "wasm_bytes": %s, "wasm_gzip_bytes": %s, "wasm_bindgen_bytes": %s, "wasm_opt_secs": %s, "build_secs": %s}' \
    "$backend" "$features" "${name}_bg.wasm" "$raw" "$gz" "$bindgen_bytes" "$opt_secs" "$((SECONDS - started))"
}

# browser_test BACKEND: the browser test of the module on BACKEND (webgl2 or webgpu); its screenshots
# and figures in target/web-test/ (webgl2) or target/web-test/webgpu/.
browser_test() {
  local backend=$1 started=$SECONDS
  local backend_out=$test_out
  [ "$backend" = webgl2 ] || backend_out=$test_out/$backend
  mkdir -p "$test_out" "$backend_out"
  # The native command line's parameters of the example, to compare with the browser's. The binary is
  # the one `cargo test` builds (its dependencies' features are the tests'; `cargo run` would build
  # them again without): up to date right after tools/test's `cargo test`.
  cargo test --quiet --no-run --test cli
  rm -f "$test_out/params-native.json"
  "$target_dir/debug/dualcal" calibrate assets/datasets/example --quiet \
    --out "$test_out/params-native.json" >"$test_out/calibrate-native.txt"
  # The example as one .zip, for the drop test (written here, not committed).
  rm -f "$backend_out/example.zip"
  python3 -m zipfile -c "$backend_out/example.zip" assets/datasets/example
  npm_ci
  DUALCAL_WEB_TEST_OUT=$backend_out node web/tests/browser-test.mjs --backend "$backend" \
    --native-params "$test_out/params-native.json"
  say "browser test on $backend done in $((SECONDS - started)) s (after the build)"
}

# The WebGPU module's size budget (issue 18: ≤ 6 MB raw, ≤ 2 MB gzip -9, MB = 10^6 bytes; raised to
# 2 020 000 gzip on 2026-12-07, a decision recorded in docs/performance.md, "Tenth pass"), from
# build.json: `tools/web.sh test` fails above it, so that growth past it is a decision, not a drift
# (docs/performance.md, "The workbench in the browser"). The WebGL2 module, for browsers without
# WebGPU, carries wgpu's shader translator and GL layer and is above it (its size is printed).
size_budget() {
  python3 - "$test_out/build.json" <<'PY'
import json, sys
budget = {"webgpu": (6_000_000, 2_020_000)}
failed = False
for m in json.load(open(sys.argv[1]))["modules"]:
    raw, gz = m["wasm_bytes"], m["wasm_gzip_bytes"]
    line = f"{m['file']}: {raw} bytes, {gz} gzip -9"
    if m["backend"] in budget:
        max_raw, max_gz = budget[m["backend"]]
        ok = raw <= max_raw and gz <= max_gz
        failed |= not ok
        line += f" — budget {max_raw} / {max_gz}: {'ok' if ok else 'OVER'}"
    print(f"tools/web.sh: {line}", file=sys.stderr)
sys.exit(1 if failed else 0)
PY
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
  serve)
    build
    port=${2:-8080}
    say "serving $out on http://127.0.0.1:$port/ (Ctrl-C stops)"
    exec python3 -m http.server "$port" --bind 127.0.0.1 --directory "$out"
    ;;
  test)
    build
    browser_test webgl2
    browser_test webgpu
    report_test
    size_budget
    ;;
  first-frame)
    [ -f "$out/index.html" ] || build
    npm_ci
    node web/tests/first-frame.mjs --loads "${2:-7}"
    ;;
  measure)
    build
    browser_test webgl2
    browser_test webgpu
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
    say "usage: tools/web.sh build | serve [PORT] | test | first-frame [N] | measure"
    exit 2
    ;;
esac
