#!/bin/bash
# E_v and DGP of heliodon's backward rendering (rpict, view v1 of the office) with the sun of one
# gendaylit sky moved to other directions, the sky itself unchanged: does a sun-patch centre
# a fraction of a degree from the exact sun change what the eye sees (a BSDF tree cell boundary,
# a peak of the transmission), independently of the annual pipeline?
#   test/bench/sun_offset.sh SKY.rad CONFIG RES < directions
# directions: lines "label dx dy dz" (any length) or "label alt=A az=Z" (degrees offsets added to the
# exact sun's altitude and azimuth).  Environment: OPTS (rpict options, "-ab 4 -ad 128 -as 0 -aa 0
# -lw 1e-4"), SEED (1), OUT (build/bench/sunoff), NPROC (2), CFSDIR (build/tmp/cfs_trees).
# Prints "label angle_to_exact_deg alt_deg az_deg E_v DGP cpu_s".
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-build}
case "$BUILD" in /*) BD=$BUILD ;; *) BD=$ROOT/$BUILD ;; esac
export PATH="$BD/bin:$PATH"
SKY=$(cd "$(dirname "$1")" && pwd)/$(basename "$1"); CONFIG=${2:-fs1}; RES=${3:-256}
OPTS=${OPTS:--ab 4 -ad 128 -as 0 -aa 0 -lw 1e-4}; SEED=${SEED:-1}; NPROC=${NPROC:-2}
OUT=${OUT:-$BD/bench/sunoff}; mkdir -p "$OUT"; OUT=$(cd "$OUT" && pwd)
CFSDIR=$(cd "${CFSDIR:-$BD/tmp/cfs_trees}" && pwd)
export RAYPATH=".:$CFSDIR"
# the exact sun: the 4 arguments of "solar source sun"
read -r sx sy sz sd <<< "$(awk '$1 == "solar" && $2 == "source" {getline; getline; getline; print $2, $3, $4, $5; exit}' "$SKY")"
while read -r label a b c; do
    [ -n "$label" ] || continue
    case $a in
    alt=*) read -r dx dy dz <<< "$(awk -v x="$sx" -v y="$sy" -v z="$sz" -v da="${a#alt=}" -v dz="${b#az=}" 'BEGIN {
        r = atan2(0, -1) / 180; al = atan2(z, sqrt(x * x + y * y)) + da * r; az = atan2(x, y) + dz * r
        printf "%.6f %.6f %.6f", cos(al) * sin(az), cos(al) * cos(az), sin(al)}')" ;;
    *) dx=$a; dy=$b; dz=$c ;;
    esac
    s=$OUT/sky_$label.rad
    awk -v x="$dx" -v y="$dy" -v z="$dz" '$1 == "solar" && $2 == "source" {print; getline; print; getline; print; getline; print 4, x, y, z, $5; next} 1' "$SKY" > "$s"
    p=$OUT/pic_${label}_s$SEED.hdr
    if [ ! -s "$p" ]; then
        (cd "$ROOT/scenes/office" && oconv "mat_$CONFIG.rad" room.rad windows.rad "$s" skyglow.rad > "$OUT/$label.oct" &&
            /usr/bin/time -f "%U %S" -o "$p.cpu" rpict -vf v1.vf -x "$RES" -y "$RES" -ps 1 -pj 0 -dj 0 $OPTS -seed "$SEED" -n "$NPROC" \
            "$OUT/$label.oct" > "$p.tmp" && mv -f "$p.tmp" "$p")
        rm -f "$OUT/$label.oct"
    fi
    awk -v x="$dx" -v y="$dy" -v z="$dz" -v sx="$sx" -v sy="$sy" -v sz="$sz" -v l="$label" \
        -v dgp="$(evalglare -vta -vh 180 -vv 180 "$p" | awk '{print $2}')" -v ev="$(evalglare -V -vta -vh 180 -vv 180 "$p")" \
        -v cpu="$(awk '{print $1 + $2}' "$p.cpu")" 'BEGIN {
        n = sqrt(x * x + y * y + z * z); c = (x * sx + y * sy + z * sz) / n / sqrt(sx * sx + sy * sy + sz * sz); if (c > 1) c = 1
        d = 180 / atan2(0, -1)
        printf "%s %.3f %.3f %.3f %s %s %.1f\n", l, d * atan2(sqrt(1 - c * c), c), d * atan2(z / n, sqrt(x * x + y * y) / n), d * atan2(x, y), ev, dgp, cpu}'
done
