#!/usr/bin/env bash
# genBSDF accuracy against CPU time (issue 22 item 5): heliodon's and
# Radiance's genBSDF on the shared clear double glazing and CFS3 prism film
# (../shared/ref/bsdf/geom), Klems full basis, light from the exterior
# (+f -b), at several -c; each result's Transmission Front against the
# converged Radiance references in test/data/genbsdf (-c 20000, see its
# MANIFEST.md) with test/data/genbsdf/klems_err.awk: mean and largest
# per-patch error of the directional-hemispherical transmittance (largest
# below 75 deg and in the grazing ring separately) and the mean element-wise
# error, in percent.  heliodon and Radiance alternate at each -c.
# Usage: BUILD=build RADIANCE=/work/rad/inst/bin test/bench/genbsdf_accuracy.sh [system [c ...]]
#   system: glazing or cfs3 (default both); c default 500 2000 8000.
#   Without RADIANCE (a folder with Radiance's genBSDF, rfluxmtx, ...) only
#   heliodon runs.  Set RC to a list of -c values to run Radiance at only
#   those (default: all of them).
set -u
BUILD=${BUILD:-build}
HD=$(cd "$BUILD/bin" && pwd)
REF=${HELIODON_REF:-../shared/ref}
DATA=$(cd test/data/genbsdf && pwd)
D=$(mktemp -d)
trap 'rm -rf "$D"' EXIT
[ -x "$HD/genBSDF" ] && [ -x "$HD/rmtxop" ] || { echo "genbsdf_accuracy: $HD/genBSDF or rmtxop not built"; exit 1; }
[ -d "$REF/bsdf/geom" ] || { echo "genbsdf_accuracy: no $REF/bsdf/geom"; exit 1; }
systems=${1:-"glazing cfs3"}
[ $# -gt 0 ] && shift
cs=${*:-"500 2000 8000"}
RC=${RC:-$cs}
TM="/usr/bin/time -f %U_%S_%e -o $D/time"
cpu() { awk -F_ '{printf "%.2f s CPU, %.1f s wall", $1 + $2, $3}' "$D/time"; }
err() { "$HD/rmtxop" -fa "$1" > "$D/m.mtx" && awk -f "$DATA/klems_err.awk" "$D/m.mtx" "$D/ref.mtx"; }
cd "$REF/bsdf" || exit 1
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "columns: tool system -c | CPU | error % mean, max below 75 deg, max grazing ring, mean element-wise"
for s in $systems; do
    case $s in
    glazing) args="-dim -50 50 -50 50 -20 0 geom/glazing.rad"; rargs=() ;;
    cfs3) args="-dim -50 50 -50 50 -4.62 0 geom/prism_glass.mat geom/cfs3.rad"; rargs=(-r "-ad 16") ;;
    *) echo "unknown system $s"; exit 1 ;;
    esac
    gunzip -c "$DATA/${s}_c20000.xml.gz" > "$D/ref.xml" && "$HD/rmtxop" -fa "$D/ref.xml" > "$D/ref.mtx" || exit 1
    for c in $cs; do
        # shellcheck disable=SC2086
        $TM nice "$HD/genBSDF" -n 1 -c "$c" +f -b -geom millimeter $args > "$D/h.xml" || exit 1
        echo "heliodon $s -c $c | $(cpu) | $(err "$D/h.xml")"
        if [ -n "${RADIANCE:-}" ] && [[ " $RC " == *" $c "* ]]; then
            # shellcheck disable=SC2086
            PATH=$RADIANCE:$PATH RAYPATH=.:$RADIANCE/../lib $TM nice "$RADIANCE/genBSDF" -n 1 -c "$c" \
                "${rargs[@]}" +f -b -geom millimeter $args > "$D/r.xml" 2> "$D/r.err" || { cat "$D/r.err"; exit 1; }
            echo "Radiance $s -c $c | $(cpu) | $(err "$D/r.xml")"
        fi
    done
done
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
