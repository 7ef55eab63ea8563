#!/usr/bin/env bash
# Three-phase method at Radiance's recorded sample counts (box scene, A3 of
# ../shared/ref/scenes/box/MANIFEST.md): V (sensors), V (fisheye pictures),
# D, then V·T·D·S vs rtrace and vs Radiance's own 3PM.  Prints agreement
# figures and run times.  Usage: BUILD=build test/bench/3pm.sh [nthreads]
set -u
BUILD=${BUILD:-build}
ROOT=$(pwd)
BIN=$ROOT/$BUILD/bin
BB=$ROOT/$BUILD/bench/bench_3pm
REF=${HELIODON_REF:-$ROOT/../shared/ref}
BOX=$REF/scenes/box
N=${1:-2}
[ -d "$BOX" ] || { echo "3pm: no reference folder $BOX"; exit 0; }
[ -x "$BB" ] || { echo "3pm: build $BB first (make bench)"; exit 1; }
OUT=${HD_TEST_TMP:-$ROOT/$BUILD/tmp}/bench_3pm
rm -rf "$OUT"; mkdir -p "$OUT/vimg"
cd "$BOX" || exit 1
t() { local s=$(date +%s.%N); "$@"; local e=$(date +%s.%N); awk -v s="$s" -v e="$e" 'BEGIN{printf "  elapsed %.1f s\n", e-s}' >&2; }

echo "== V (sensors): rfluxmtx -faf -y 28 -I+ -ab 8 -ad 32768 -lw 1e-6 - window_rx_pts.rad box_room.rad (-n $N)"
/usr/bin/time -f "  user %U s, elapsed %e s, max RSS %M kB" \
    "$BIN/rfluxmtx" -n "$N" -faf -y 28 -I+ -ab 8 -ad 32768 -lw 1e-6 - window_rx_pts.rad box_room.rad \
    < sensors.pts > "$OUT/V.vmx"
"$BB" stats "$OUT/V.vmx" a3_V_sensors.vmx

echo "== V at 4x the samples (-ad 131072; about Radiance's CPU time for -ad 32768)"
/usr/bin/time -f "  user %U s, elapsed %e s, max RSS %M kB" \
    "$BIN/rfluxmtx" -n "$N" -faf -y 28 -I+ -ab 8 -ad 131072 -lw 1e-6 - window_rx_pts.rad box_room.rad \
    < sensors.pts > "$OUT/V4.vmx"
"$BB" stats "$OUT/V4.vmx" a3_V_sensors.vmx

echo "== V converged (-ad 524288 -lw 1e-7): how noisy is the reference itself?"
/usr/bin/time -f "  user %U s, elapsed %e s, max RSS %M kB" \
    "$BIN/rfluxmtx" -n "$N" -faf -y 28 -I+ -ab 8 -ad 524288 -lw 1e-7 - window_rx_pts.rad box_room.rad \
    < sensors.pts > "$OUT/V16.vmx"
echo "  Radiance's a3_V_sensors.vmx vs heliodon converged:"
"$BB" stats a3_V_sensors.vmx "$OUT/V16.vmx"
echo "  heliodon -ad 32768 vs heliodon converged:"
"$BB" stats "$OUT/V.vmx" "$OUT/V16.vmx"

if [ -n "${RADIANCE_BIN:-}" ] && [ -x "$RADIANCE_BIN/rfluxmtx" ]; then
    echo "== Radiance's own command re-run (RADIANCE_BIN): the reference's Monte Carlo noise"
    RAYPATH=.:$(cd "$RADIANCE_BIN/../lib" 2>/dev/null && pwd) PATH=$RADIANCE_BIN:$PATH /usr/bin/time -f "  user %U s, elapsed %e s" \
        "$RADIANCE_BIN/rfluxmtx" -n "$N" -faf -y 28 -I+ -ab 8 -ad 32768 -lw 1e-6 - window_rx_pts.rad box_room.rad \
        < sensors.pts > "$OUT/VR.vmx"
    echo "  Radiance re-run vs a3_V_sensors.vmx:"
    "$BB" stats "$OUT/VR.vmx" a3_V_sensors.vmx
    echo "  Radiance re-run vs heliodon converged:"
    "$BB" stats "$OUT/VR.vmx" "$OUT/V16.vmx"
fi

echo "== D: rfluxmtx -ff -c 2000 -ab 2 -ad 512 -lw 1e-4 window_tx.rad sky_rx.rad box_room.rad (-n $N)"
/usr/bin/time -f "  user %U s, elapsed %e s, max RSS %M kB" \
    "$BIN/rfluxmtx" -n "$N" -ff -c 2000 -ab 2 -ad 512 -lw 1e-4 window_tx.rad sky_rx.rad box_room.rad > "$OUT/D.dmx"
"$BB" stats "$OUT/D.dmx" a3_D.dmx

echo "== V (fisheye 128x128 per Klems bin): vwrays -ff -x 128 -y 128 -vf fish.vf | rfluxmtx -ffc -x 128 -y 128 -ld- -ab 6 -ad 1024 -lw 1e-4 (-n $N)"
sed "s|o=a3_vimg/v%03d.hdr|o=$OUT/vimg/v%03d.hdr|" window_rx_img.rad > "$OUT/window_rx_img.rad"
"$BIN/vwrays" -ff -x 128 -y 128 -vf fish.vf > "$OUT/fish.rays"
/usr/bin/time -f "  user %U s, elapsed %e s, max RSS %M kB" \
    "$BIN/rfluxmtx" -n "$N" -ffc -x 128 -y 128 -ld- -ab 6 -ad 1024 -lw 1e-4 - "$OUT/window_rx_img.rad" box_room.rad < "$OUT/fish.rays"
echo "  per-bin picture means vs a3_vimg:"
"$BB" pics "$OUT/vimg/v%03d.hdr" "a3_vimg/v%03d.hdr.gz" 145

echo "== 3PM: V T D S (T = Klems tb of glass_klems.xml via the bsdf module)"
"$BB" tmatrix glass_klems.xml "$OUT/T.mtx"
"$BB" fold "$OUT/V.vmx" "$OUT/T.mtx" "$OUT/D.dmx" a3_sky_mf1.smx a1_clear_conv.dat a1_overcast_conv.dat a3_res_sensors_skysun.mtx
echo "== same fold with Radiance's V and D (checks T and the multiplication)"
"$BB" fold a3_V_sensors.vmx "$OUT/T.mtx" a3_D.dmx a3_sky_mf1.smx a1_clear_conv.dat a1_overcast_conv.dat a3_res_sensors_skysun.mtx
