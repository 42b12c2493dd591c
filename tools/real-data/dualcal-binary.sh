# Sourced by the scripts here: `dualcal_binary DIR` prints the dualcal to run — $DUALCAL, else
# `dualcal` on PATH, else the release build of the checkout DIR/../.. (built if needed).
dualcal_binary() {
    if [ -n "${DUALCAL:-}" ]; then
        echo "$DUALCAL"
    elif command -v dualcal >/dev/null 2>&1; then
        echo dualcal
    else
        local root
        root=$(cd "$1/../.." && pwd)
        (cd "$root" && cargo build --release --quiet --bin dualcal) >&2
        echo "$root/target/release/dualcal"
    fi
}
