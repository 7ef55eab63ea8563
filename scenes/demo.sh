#!/bin/bash
# make demo: the annual PM-CBDM glare assessment of the office (scenes/office), view v1, for a
# synthetic Izmir weather year (genwea, 38.4 N 27.1 E, UTC+2), configuration FS1 (data-driven)
# when its BSDF files and BSDF tracing are available, otherwise clear glass (said plainly).
# Settings sized to finish in well under 20 minutes on 2 idle cores; override with
#   DEMO_RES, DEMO_MF, DEMO_PHOTONS, DEMO_BANDWIDTH, DEMO_CONFIG, DEMO_WEATHER, DEMO_OUT, NPROC,
#   DEMO_TREES (0: do not make missing tensor trees), DEMO_FENSUN_OPTS / DEMO_FENSUN_C (the refined
#   sun DC of the window pixels; lighter than the Makefile's default to keep the demo short).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${BUILD:-build}
case "$BUILD" in /*) BIN=$BUILD/bin ;; *) BIN=$ROOT/$BUILD/bin ;; esac
export PATH="$BIN:$PATH"
OUT=${DEMO_OUT:-$ROOT/$BUILD/demo}
RES=${DEMO_RES:-128}
MF=${DEMO_MF:-1}
PHOTONS=${DEMO_PHOTONS:-1m}
BANDWIDTH=${DEMO_BANDWIDTH:-50}
NPROC=${NPROC:-2}
CONFIG=${DEMO_CONFIG:-fs1}
CFSDIR=${CFSDIR:-$ROOT/scenes/cfs}
mkdir -p "$OUT"
say() { echo "demo: $*"; }
for t in genwea gensuns mkpmap rcontrib rpict vwrays oconv pmmask pmcompose cbdmreport; do
    command -v "$t" >/dev/null || { say "missing program $t in $BIN (run make first)" >&2; exit 1; }
done

# 1. weather: a synthetic year for Izmir unless a file is given
if [ -n "${DEMO_WEATHER:-}" ]; then
    WEATHER=$DEMO_WEATHER
    say "weather file $WEATHER"
else
    WEATHER=$OUT/izmir_synthetic.wea
    genwea -a 38.4 -o -27.1 -m -30 -e 25 -n Izmir "$WEATHER"
    say "synthetic Izmir weather year (genwea -a 38.4 -o -27.1 -m -30) -> $WEATHER"
fi

# 2. configuration: FS1 needs its tensor-tree XMLs (scenes/cfs) and BSDF support in the tracer.
#    Missing tensor trees are made by genBSDF from scenes/cfs's geometry in $OUT/cfs (a copy, so
#    that the repository's XML files are never rewritten); DEMO_TREES=0 skips that.
skipped=()
SKYARGS=()
if [ "$CONFIG" != glass ]; then
    need=$(awk '$2=="BSDF"{print $6}' "$ROOT/scenes/office/mat_$CONFIG.rad" | sort -u)
    missing=""
    for x in $need; do [ -r "$CFSDIR/$x" ] || missing="$missing $x"; done
    if [ -n "$missing" ] && [ "${DEMO_TREES:-1}" = 1 ] && command -v genBSDF >/dev/null; then
        mkdir -p "$OUT/cfs"
        for f in "$ROOT"/scenes/cfs/*; do [ -e "$OUT/cfs/$(basename "$f")" ] || cp -p "$f" "$OUT/cfs/"; done
        say "making the tensor trees$missing with genBSDF (scenes/cfs geometry, $NPROC threads) in $OUT/cfs"
        tt0=$(date +%s)
        make -s -C "$OUT/cfs" GENBSDF="$BIN/genBSDF" NPROC="$NPROC" $missing
        TREES_S=$(( $(date +%s) - tt0 ))
        say "tensor trees made in $TREES_S s"
        CFSDIR=$OUT/cfs
        missing=""
        for x in $need; do [ -r "$CFSDIR/$x" ] || missing="$missing $x"; done
    fi
    bsdf_ok=1
    if [ -z "$missing" ]; then
        # can the tracer pass light through a BSDF material?  A photon map through a BSDF port
        # (a tracer without BSDF scattering stores no photons behind it)
        x=$(awk '$2=="BSDF"{print $6; exit}' "$ROOT/scenes/office/mat_$CONFIG.rad")
        { printf 'void light s 0 0 3 1 1 1\ns source sun 0 0 4 0 0 1 0.5\n'
          printf 'void plastic f 0 0 5 .5 .5 .5 0 0\nf polygon fl 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n'
          printf 'void BSDF t 6 0 %s 0 1 0 . 0 0\nt polygon p 0 0 12 0 0 1 0 1 1 1 1 1 1 0 1\n' "$x"; } > "$OUT/bsdf_probe.rad"
        if ! (cd "$OUT" && rm -f bsdf_probe.cpm && oconv bsdf_probe.rad > bsdf_probe.oct &&
              RAYPATH=".:$CFSDIR" mkpmap -apC bsdf_probe.cpm 4k -apo t bsdf_probe.oct) > /dev/null 2> "$OUT/bsdf_probe.err" ||
           grep -q 'no photons stored\|no light source' "$OUT/bsdf_probe.err"; then
            bsdf_ok=0
        fi
    fi
    if [ -n "$missing" ]; then
        say "configuration $CONFIG skipped: BSDF file(s)$missing not in $CFSDIR (made by scenes/cfs); using clear glass instead"
        skipped+=("configuration $CONFIG (BSDF files$missing missing) -> glass")
        CONFIG=glass
    elif [ $bsdf_ok = 0 ]; then
        say "configuration $CONFIG skipped: the tracer cannot use BSDF materials yet ($(grep -v '^$' "$OUT/bsdf_probe.err" | head -1)); using clear glass"
        skipped+=("configuration $CONFIG (no BSDF tracing) -> glass")
        CONFIG=glass
    fi
fi
# FS1's sky part by the three-phase split per window group (V, T = Klems BSDF, D) when the Klems
# XMLs are there; the sun part and the refined fenestration DC trace the tensor trees
if [ "$CONFIG" = fs1 ] && [ -r "$ROOT/scenes/cfs/cfs1_klems.xml" ] && [ -r "$ROOT/scenes/cfs/cfs2_klems.xml" ]; then
    SKYARGS=(SKYMETHOD=3pm KLEMS_WG1="$ROOT/scenes/cfs/cfs1_klems.xml" KLEMS_WG2="$ROOT/scenes/cfs/cfs2_klems.xml")
fi

# 3. the annual run (scenes/office/Makefile)
RUN=$OUT/office_${CONFIG}_v1
mkdir -p "$RUN"
{
    echo "demo (scenes/demo.sh), $(date -u '+%Y-%m-%d %H:%M UTC')"
    echo "weather: $WEATHER"
    echo "pipeline: gensuns -> mkpmap -apC -> rcontrib -ap (DC_sun); sky part (below);"
    echo "  fenestration mask (rpict) -> refined backward sky and sun DCs inside it; pmcompose (streamed glare); cbdmreport"
    if [ ${#SKYARGS[@]} -gt 0 ]; then
        echo "sky part: three-phase split per window group: V (rfluxmtx), T (Klems XML of scenes/cfs), D (rfluxmtx);"
        echo "  sun part and refined fenestration DC through the tensor-tree BSDFs ($CFSDIR)"
    else
        echo "sky part: daylight coefficients traced through the windows by rcontrib (SKYMETHOD=dc)"
    fi
    [ -n "${TREES_S:-}" ] && echo "tensor trees by genBSDF in $CFSDIR (made in this run: $TREES_S s)"
    for s in "${skipped[@]+"${skipped[@]}"}"; do echo "skipped: $s"; done
} > "$RUN/demo_notes.txt"
cat "$RUN/demo_notes.txt"
say "annual run: config $CONFIG, view v1, ${RES}x${RES}, sun MF:$MF, $PHOTONS photons, bandwidth $BANDWIDTH, $NPROC threads"
t0=$(date +%s)
make -s -C "$ROOT/scenes/office" WEATHER="$WEATHER" CONFIG=$CONFIG VIEW=v1 RES=$RES MF=$MF PHOTONS=$PHOTONS \
     BANDWIDTH=$BANDWIDTH NPROC=$NPROC CFSDIR="$CFSDIR" OUT="$RUN" NOTES="$RUN/demo_notes.txt" \
     FENSUN_OPTS="${DEMO_FENSUN_OPTS:--ab 1 -ad 64 -lw 1e-3}" FENSUN_C="${DEMO_FENSUN_C:-4}" \
     "${SKYARGS[@]+"${SKYARGS[@]}"}" 2>&1 |
    { grep -v 'no emission through the photon ports' || true; }
say "(mkpmap: suns behind the facade emit no photons through the window ports; their warnings are not shown)"
t1=$(date +%s)
say "stage timings (s):"
sed 's/^/  /' "$RUN/timings.txt"
[ -n "${TREES_S:-}" ] && say "  (tensor trees: $TREES_S s before the run)"
say "total $((t1 - t0)) s"
say "report: $RUN/report/index.html"

# 4. FS1's sky part by the three-phase method with the Klems BSDFs of scenes/cfs, when FS1 itself
#    could not run (no direct sun: the tracer cannot pass the sun through BSDF windows yet)
if [ "$CONFIG" = glass ] && [ "${DEMO_CONFIG:-fs1}" = fs1 ] && [ -r "$CFSDIR/cfs1_klems.xml" ] && [ -r "$CFSDIR/cfs2_klems.xml" ]; then
    RUN2=$OUT/office_fs1k_v1_sky3pm
    mkdir -p "$RUN2"
    {
        echo "FS1 (wg1 CFS1, wg2+wg3 CFS2; Klems BSDFs of scenes/cfs), SKY PART ONLY: three-phase V (rfluxmtx per"
        echo "window group), D (rfluxmtx window -> sky), T (Klems XML), diffuse sky vectors of every hour."
        echo "The direct sun is NOT included (the tracer has no BSDF material yet, so neither the photon map"
        echo "nor the backward DC can pass the sun through the CFS): glare figures are for the diffuse sky only."
    } > "$RUN2/demo_notes.txt"
    say "FS1 sky part (three-phase, Klems BSDFs, no direct sun): $RUN2"
    t2=$(date +%s)
    make -s -C "$ROOT/scenes/office" WEATHER="$WEATHER" CONFIG=fs1k VIEW=v1 RES=$RES NPROC=$NPROC CFSDIR="$CFSDIR" \
         SKYMETHOD=3pm KLEMS_WG1="$CFSDIR/cfs1_klems.xml" KLEMS_WG2="$CFSDIR/cfs2_klems.xml" SUN=0 FEN=0 \
         OUT="$RUN2" NOTES="$RUN2/demo_notes.txt"
    say "FS1 sky part: $(( $(date +%s) - t2 )) s; stage timings (s):"
    sed 's/^/  /' "$RUN2/timings.txt"
    say "report (FS1, sky only): $RUN2/report/index.html"
fi
