#!/usr/bin/env bash
# DLR's Agile Justin, calibrated with dualcal commands (issue 20; docs/real-data.md).
#
#   tools/real-data/dlr-justin.sh RAW_CSV OUT [--model MODEL] [--robot DH_FILE]
#
# MODEL: the model identified with the geometry (`dualcal calibrate --model`: geometric, the default;
# elastic-axis, elastic, harmonic, full — issue 21). DH_FILE: the robot (default dlr-justin.dh.toml).
#
# RAW_CSV: DLR's dataset/measurements.csv (dlr-alr/dlr-elastic-calibration at commit b74d13b; never
# committed here). OUT gets:
#   dataset/               the imported dualcal-dataset/1 (first 400 rows calibrate, last 100 verify)
#   params-nominal.json    the camera frame and the marker points fitted, the kinematics nominal
#   params-geometric.json  the geometric calibration (--method position: both arms, the shared torso
#                          once, one camera frame)
#   params.json            the calibration with MODEL (the same file as params-geometric.json's
#                          content for the geometric model)
#   calibrated.urdf        the calibrated robot's geometry (markers as reflector links)
#   evaluate-ver.json      `dualcal evaluate --json` of params.json on the verification rows
#   evaluate-ver-nominal.json, evaluate-ver-geometric.json, absolute-ver*.csv (every marker's error)
# and prints the table. DUALCAL names the binary (default: `dualcal` on PATH, else the release build
# of this checkout, built if needed).
set -euo pipefail

usage() {
    echo "usage: $0 RAW_CSV OUT [--model MODEL] [--robot DH_FILE]" >&2
    exit 2
}
[ $# -ge 2 ] || usage
raw=$1
out=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
robot="$here/dlr-justin.dh.toml"
model=geometric
while [ $# -gt 0 ]; do
    case $1 in
    --robot)
        [ $# -ge 2 ] || usage
        robot=$2
        shift 2
        ;;
    --model)
        [ $# -ge 2 ] || usage
        model=$2
        shift 2
        ;;
    *) usage ;;
    esac
done
[ -f "$raw" ] || { echo "$raw: no such file" >&2; exit 2; }
[ -f "$robot" ] || { echo "$robot: no such file" >&2; exit 2; }

# shellcheck source=dualcal-binary.sh
. "$here/dualcal-binary.sh"
dualcal=$(dualcal_binary "$here")

mkdir -p "$out"
# Row 0 of the markers matrix is the right hand, row 1 the left (tools/real-data/README.md); the
# 19 values are torso 3, right 7, left 7, head 2; the passive torso joint, -(tilt 1 + tilt 2), is the
# robot file's coupling (no column).
"$dualcal" import --robot "$robot" \
    --left-points "$raw" --right-points "$raw" \
    --left-columns "id=1,q=joints[0-2],q=joints[10-16],m.x=markers[1][0],m.y=markers[1][1],m.z=markers[1][2]" \
    --right-columns "id=1,q=joints[0-2],q=joints[3-9],m.x=markers[0][0],m.y=markers[0][1],m.z=markers[0][2]" \
    --length-unit m --angle-unit rad \
    --reflector m=-100,0,75 --left-reflector m=-100,30,50 --right-reflector m=-100,-30,100 \
    --measured-together --verify-last 100 --force --out "$out/dataset" >"$out/import.log"

# Nominal: only the camera frame and the marker points fitted (on the calibration rows).
"$dualcal" calibrate "$out/dataset" --method position --hold-kinematics --quiet \
    --out "$out/params-nominal.json" >"$out/calibrate-nominal.log" 2>&1
# Geometric calibration: every identifiable joint-origin correction, the torso once, one camera frame.
"$dualcal" calibrate "$out/dataset" --method position --quiet \
    --out "$out/params-geometric.json" --urdf "$out/calibrated.urdf" >"$out/calibrate-geometric.log" 2>&1
# The chosen model, identified with the geometry (the same fit for the geometric model).
if [ "$model" = geometric ]; then
    cp "$out/params-geometric.json" "$out/params.json"
    cp "$out/calibrate-geometric.log" "$out/calibrate.log"
else
    "$dualcal" calibrate "$out/dataset" --method position --model "$model" --quiet \
        --out "$out/params.json" --urdf "$out/calibrated.urdf" >"$out/calibrate.log" 2>&1
fi

for which in nominal geometric model; do
    case $which in
    nominal) params="$out/params-nominal.json" suffix="-nominal" ;;
    geometric) params="$out/params-geometric.json" suffix="-geometric" ;;
    model) params="$out/params.json" suffix="" ;;
    esac
    "$dualcal" evaluate "$out/dataset" --params "$params" --split ver --json \
        --absolute-csv "$out/absolute-ver$suffix.csv" >"$out/evaluate-ver$suffix.json"
done

# The table: the marker (TCP) position error in the camera frame on the 100 verification rows.
row() { # label, csv
    awk -F, -v label="$1" 'NR > 1 { e = $4; s += e; q += e * e; if (e > m) m = e; n++ }
        END { printf "%-52s %8.2f %8.2f %8.2f %6d\n", label, s / n, sqrt(q / n), m, n }' "$2"
}
echo "DLR Agile Justin, last 100 rows (verification), marker position error in the camera frame, mm"
printf "%-52s %8s %8s %8s %6s\n" "model" "mean" "RMS" "max" "points"
row "nominal (camera frame and markers fitted)" "$out/absolute-ver-nominal.csv"
row "geometric calibration (--method position)" "$out/absolute-ver-geometric.csv"
if [ "$model" != geometric ]; then
    row "$model model (--method position --model $model)" "$out/absolute-ver.csv"
fi
echo
echo "histogram (2 mm bins): nominal | $model"
awk -F, 'FNR == 1 { f++; next } { b = int($4 / 2); if (b > 30) b = 30; c[f, b]++; if (b > top) top = b }
    END { for (b = 0; b <= top; b++) {
        lo = 2 * b; label = (b == 30) ? sprintf(">= %2d", lo) : sprintf("%2d-%2d", lo, lo + 2);
        bar1 = ""; for (i = 0; i < c[1, b]; i++) bar1 = bar1 "#";
        bar2 = ""; for (i = 0; i < c[2, b]; i++) bar2 = bar2 "#";
        printf "%s mm %3d %-40s | %3d %s\n", label, c[1, b], bar1, c[2, b], bar2 } }' \
    "$out/absolute-ver-nominal.csv" "$out/absolute-ver.csv"
echo
echo "check_urdf-valid calibrated robot: $out/calibrated.urdf; figures: $out/evaluate-ver.json"
