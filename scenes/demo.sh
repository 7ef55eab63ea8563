#!/bin/bash
# make demo: the annual PM-CBDM glare assessment of the office (scenes/office), view v1, for a
# synthetic Izmir weather year (genwea, 38.4 N 27.1 E, UTC+2), configuration FS1 (data-driven)
# when its BSDF files and BSDF tracing are available, otherwise clear glass (said plainly).
# Settings sized to finish in well under 20 minutes on 2 idle cores; override with
#   DEMO_RES, DEMO_MF, DEMO_PHOTONS, DEMO_BANDWIDTH, DEMO_CONFIG, DEMO_WEATHER, DEMO_OUT, NPROC.
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

# 2. configuration: FS1 needs its tensor-tree XMLs (scenes/cfs) and BSDF support in the tracer
skipped=()
if [ "$CONFIG" != glass ]; then
    missing=""
    for x in $(awk '$2=="BSDF"{print $6}' "$ROOT/scenes/office/mat_$CONFIG.rad" | sort -u); do
        [ -r "$CFSDIR/$x" ] || missing="$missing $x"
    done
    bsdf_ok=1
    if [ -z "$missing" ]; then
        # can the tracer use a BSDF material? (one ray through a tiny scene)
        x=$(awk '$2=="BSDF"{print $6; exit}' "$ROOT/scenes/office/mat_$CONFIG.rad")
        printf 'void BSDF t 6 0 %s 0 0 1 . 0 0\nt polygon p 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0\n' "$x" > "$OUT/bsdf_probe.rad"
        echo "0.5 0.5 1 0 0 -1" | RAYPATH=".:$CFSDIR" rtrace -h "$OUT/bsdf_probe.rad" >/dev/null 2>"$OUT/bsdf_probe.err" || bsdf_ok=0
    fi
    if [ -n "$missing" ]; then
        say "configuration $CONFIG skipped: BSDF file(s)$missing not in $CFSDIR (made by scenes/cfs); using clear glass instead"
        skipped+=("configuration $CONFIG (BSDF files$missing missing) -> glass")
        CONFIG=glass
    elif [ $bsdf_ok = 0 ]; then
        say "configuration $CONFIG skipped: the tracer cannot use BSDF materials yet ($(head -1 "$OUT/bsdf_probe.err")); using clear glass"
        skipped+=("configuration $CONFIG (no BSDF tracing) -> glass")
        CONFIG=glass
    fi
fi

# 3. the annual run (scenes/office/Makefile)
RUN=$OUT/office_${CONFIG}_v1
mkdir -p "$RUN"
{
    echo "demo (scenes/demo.sh), $(date -u '+%Y-%m-%d %H:%M UTC')"
    echo "weather: $WEATHER"
    echo "pipeline: gensuns -> mkpmap -apC -> rcontrib -ap (DC_sun); rcontrib sky DC (MF:1);"
    echo "  fenestration mask (rpict) -> refined rcontrib DC inside it; pmcompose (streamed glare); cbdmreport"
    echo "sky part: daylight coefficients traced through the windows by rcontrib (SKYMETHOD=dc); the"
    echo "  three-phase split per window group (SKYMETHOD=3pm) needs the groups' Klems BSDFs"
    for s in "${skipped[@]+"${skipped[@]}"}"; do echo "skipped: $s"; done
} > "$RUN/demo_notes.txt"
cat "$RUN/demo_notes.txt"
say "annual run: config $CONFIG, view v1, ${RES}x${RES}, sun MF:$MF, $PHOTONS photons, bandwidth $BANDWIDTH, $NPROC threads"
t0=$(date +%s)
make -s -C "$ROOT/scenes/office" WEATHER="$WEATHER" CONFIG=$CONFIG VIEW=v1 RES=$RES MF=$MF PHOTONS=$PHOTONS \
     BANDWIDTH=$BANDWIDTH NPROC=$NPROC CFSDIR="$CFSDIR" OUT="$RUN" NOTES="$RUN/demo_notes.txt" 2>&1 |
    { grep -v 'no emission through the photon ports' || true; }
say "(mkpmap: suns behind the facade emit no photons through the window ports; their warnings are not shown)"
t1=$(date +%s)
say "stage timings (s):"
sed 's/^/  /' "$RUN/timings.txt"
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
