#!/usr/bin/env bash
# How much of DLR's Agile Justin data a model can explain, beyond the one 400/100 split of
# dlr-justin.sh (issue 21; docs/real-data.md):
#
#   tools/real-data/dlr-justin-splits.sh OUT [--models "geometric elastic full"] [--seeds N]
#
# OUT is the output directory of `tools/real-data/dlr-justin.sh RAW_CSV OUT` (its imported dataset
# is read, never changed). For each model it prints
#   - the fixed split's figures (first 400 rows calibrate, last 100 verify), the issue's protocol;
#   - the same model fitted to all 500 rows, evaluated on the last 100: what the model can reach on
#     those rows when it has seen them (a floor for any fit of that model from the first 400);
#   - N random 400/100 splits (seeds 1..N; the rows by id, both arms alike): min, mean, max.
# Mean marker position error in the camera frame on the verification rows, mm. DUALCAL names the
# binary (default: `dualcal` on PATH, else this checkout's release build, built if needed).
set -euo pipefail

usage() {
    echo "usage: $0 OUT [--models \"M1 M2 …\"] [--seeds N]" >&2
    exit 2
}
[ $# -ge 1 ] || usage
out=$1
shift
models="geometric elastic full"
seeds=8
while [ $# -gt 0 ]; do
    case $1 in
    --models)
        [ $# -ge 2 ] || usage
        models=$2
        shift 2
        ;;
    --seeds)
        [ $# -ge 2 ] || usage
        seeds=$2
        shift 2
        ;;
    *) usage ;;
    esac
done
dataset="$out/dataset"
[ -f "$dataset/dataset.toml" ] || {
    echo "$dataset/dataset.toml: no such file (run tools/real-data/dlr-justin.sh first)" >&2
    exit 2
}
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=dualcal-binary.sh
. "$here/dualcal-binary.sh"
dualcal=$(dualcal_binary "$here")

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# mean of the verification rows' errors of params $2 on dataset $1
mean_ver() {
    "$dualcal" evaluate "$1" --params "$2" --split ver --json --absolute-csv "$work/abs.csv" >/dev/null
    awk -F, 'NR > 1 { s += $4; n++ } END { printf "%.2f", s / n }' "$work/abs.csv"
}
fit() { # dataset, model, split, out
    "$dualcal" calibrate "$1" --method position --model "$2" --split "$3" --quiet --out "$4" \
        >"$work/calibrate.log" 2>&1 || {
        cat "$work/calibrate.log" >&2
        exit 1
    }
}
# A copy of the dataset whose split column verifies the rows of ids in file $2.
resplit() { # dataset copy dir, ids file
    for arm in left right; do
        awk -F, -v OFS=, -v ids="$2" 'BEGIN { while ((getline id < ids) > 0) ver[id] = 1 }
            /^#/ || /^id,/ { print; next }
            { $NF = ($1 in ver) ? "ver" : "cal"; print }' "$dataset/$arm.csv" >"$1/$arm.csv"
    done
}

cp -r "$dataset" "$work/split"
ids=$(awk -F, '!/^#/ && !/^id,/ { print $1 }' "$dataset/left.csv")
printf "%-12s %10s %14s %26s\n" "model" "400/100" "all 500 fit" "random 400/100: min mean max"
for model in $models; do
    fit "$dataset" "$model" cal "$work/p.json"
    fixed=$(mean_ver "$dataset" "$work/p.json")
    fit "$dataset" "$model" all "$work/p.json"
    all=$(mean_ver "$dataset" "$work/p.json")
    figures=""
    for seed in $(seq 1 "$seeds"); do
        # The rows shuffled by awk's generator with this seed; the first 100 verify.
        echo "$ids" | awk -v seed="$seed" 'BEGIN { srand(seed) } { print rand(), $1 }' |
            sort -g | awk 'NR <= 100 { print $2 }' >"$work/ver-ids"
        resplit "$work/split" "$work/ver-ids"
        fit "$work/split" "$model" cal "$work/p.json"
        figures="$figures $(mean_ver "$work/split" "$work/p.json")"
    done
    random=$(echo "$figures" | awk '{ lo = $1; hi = $1; s = 0
        for (i = 1; i <= NF; i++) { s += $i; if ($i < lo) lo = $i; if ($i > hi) hi = $i }
        printf "%.2f %.2f %.2f", lo, s / NF, hi }')
    printf "%-12s %10s %14s %26s\n" "$model" "$fixed" "$all" "$random"
done
echo "(mean marker position error on the verification rows, mm; $seeds random splits)"
