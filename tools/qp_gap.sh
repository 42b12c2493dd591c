#!/bin/sh
# How far the paper's subgradient QP ends from the exact QP, stage by stage (docs/solver.md, "Exact
# against paper QP"): for each seed, `dualcal simulate --seed N` (the paper-size protocol), then
# `dualcal calibrate` with `--qp exact` and with `--qp paper`; prints each stage's relative ψ gap
# (paper / exact − 1, from the parameter files' `psi_mm2`: left arm, right arm, base) and both runs'
# `total time`.
#
#   tools/qp_gap.sh [--bin target/release/dualcal] 1 2 3 4 5 6 7 8
set -eu
BIN=target/release/dualcal
if [ "${1:-}" = "--bin" ]; then BIN=$2; shift 2; fi
[ $# -gt 0 ] || { echo "usage: $0 [--bin DUALCAL] SEED..." >&2; exit 2; }
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
for seed in "$@"; do
  "$BIN" simulate --out "$WORK/sim$seed" --seed "$seed" > /dev/null
  for qp in exact paper; do
    "$BIN" calibrate "$WORK/sim$seed" --out "$WORK/$seed-$qp.json" --qp "$qp" \
      > "$WORK/out" 2> "$WORK/log" || { cat "$WORK/log" >&2; exit 1; }
    sed -n "s/^total time \([0-9.]*\) s.*/$seed $qp \1/p" "$WORK/out" >> "$WORK/times"
  done
done
python3 - "$WORK" "$@" <<'PY'
import json, sys
work, seeds = sys.argv[1], sys.argv[2:]
times = {}
for line in open(f"{work}/times"):
    seed, qp, t = line.split()
    times[(seed, qp)] = float(t)
def psi(seed, qp):
    d = json.load(open(f"{work}/{seed}-{qp}.json"))
    return [stage["psi_mm2"] for stage in d["termination"]]
worst = 0.0
print("seed  gap left    gap right   gap base    time exact  time paper (s)")
for seed in seeds:
    gaps = [p / e - 1.0 for e, p in zip(psi(seed, "exact"), psi(seed, "paper"))]
    worst = max([worst] + [abs(g) for g in gaps[:2]])
    print(f"{seed:>4}  " + "  ".join(f"{g:+.2e}" for g in gaps)
          + f"   {times[(seed, 'exact')]:.3f}       {times[(seed, 'paper')]:.3f}")
print(f"largest arm-stage gap {worst:.2e}")
PY
