#!/usr/bin/env bash
# compare_builds.sh — speed of this tree's build against git revision REV,
# measured in the same run: REV is built in a temporary folder outside the
# project (removed at the end); then every benchmark runs alternately with
# the old and the new programs (old first in odd rounds, new first in even
# ones), ROUNDS times at each thread count, and the medians of wall and CPU
# (user + system of the benchmark's processes) are printed with the new/old
# ratio and PASS when the ratio of the judged figure is at most 1 + TOL.
# The outputs of the first round are compared too ("same" / "differ").
#
# Usage: test/bench/compare_builds.sh [-r ROUNDS] [-n "1 2"] [-m cpu|wall]
#                                     [-t TOL] REV [BENCHMARK...]
#   -r ROUNDS  runs of each build per benchmark and thread count (default 5)
#   -n LIST    thread counts (-n of the programs; default "1 2")
#   -m cpu|wall  the figure judged (default cpu: steadier on a shared machine)
#   -t TOL     tolerance (default 0.05)
#   BENCHMARK  any of: rtrace rpict rcontrib rcontrib_ap mkpmap dctimestep
#              genbsdf pmcompose (default: all)
# Environment: BUILD (this tree's build folder, default build), TMPDIR,
# COMPARE_SCALE (sizes of the inputs; 1 = benchmarks of about 2-6 s CPU each
# at -n 1 on the machine of docs/benchmarks.md, 0.25 for a quick check; below
# ~0.5 s a run's CPU time is only good to ~10 %, the clock tick),
# COMPARE_OLD_BIN (a folder with REV's programs already built: not rebuilt).
# Example: nice test/bench/compare_builds.sh -r 3 main rcontrib_ap mkpmap
# (make compare-builds REV=main BENCH="rcontrib_ap mkpmap")
set -u
ROUNDS=5 NLIST="1 2" METRIC=cpu TOL=0.05
while getopts r:n:m:t: opt; do
    case $opt in
    r) ROUNDS=$OPTARG ;; n) NLIST=$OPTARG ;; m) METRIC=$OPTARG ;; t) TOL=$OPTARG ;;
    *) sed -n '12,19p' "$0" >&2; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
[ $# -ge 1 ] || { sed -n '12,19p' "$0" >&2; exit 2; }
REV=$1; shift
ALL="rtrace rpict rcontrib rcontrib_ap mkpmap dctimestep genbsdf pmcompose"
BENCHES=${*:-$ALL}
for b in $BENCHES; do
    case " $ALL " in *" $b "*) ;; *) echo "compare_builds: unknown benchmark $b (one of: $ALL)" >&2; exit 2 ;; esac
done
case $METRIC in cpu|wall) ;; *) echo "compare_builds: -m cpu or wall" >&2; exit 2 ;; esac
SCALE=${COMPARE_SCALE:-1}
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
NEWBIN=$ROOT/${BUILD:-build}/bin
export SOURCE_DATE_EPOCH=1000000000 RAYPATH=.:$ROOT/lib

W=$(mktemp -d "${TMPDIR:-/tmp}/hdcompare.XXXXXX") || exit 1
trap 'rm -rf "$W"' EXIT
trap 'exit 130' INT TERM
case $W in "$ROOT"/*) echo "compare_builds: TMPDIR must lie outside the project" >&2; exit 2 ;; esac
log() { echo "compare_builds: $*" >&2; }

# ---- the two builds ----
old_id=$(git -C "$ROOT" rev-parse --short "$REV^{commit}") || exit 1
new_id="$(git -C "$ROOT" rev-parse --short HEAD)$(git -C "$ROOT" diff --quiet HEAD -- src tools include Makefile || echo +changes)"
OLDBIN=${COMPARE_OLD_BIN:-$W/old/build/bin}
if [ -z "${COMPARE_OLD_BIN:-}" ]; then
    log "building $REV ($old_id) in $W/old"
    mkdir -p "$W/old"
    git -C "$ROOT" archive --format=tar "$old_id" | tar -x -C "$W/old" || exit 1
    make -C "$W/old" -j2 all > "$W/old.build.log" 2>&1 || { tail -20 "$W/old.build.log" >&2; exit 1; }
fi
log "building this tree ($new_id)"
make -C "$ROOT" -j2 all > "$W/new.build.log" 2>&1 || { tail -20 "$W/new.build.log" >&2; exit 1; }

# ---- inputs, made once with the new programs ----
scaled() { awk -v a="$1" -v s="$SCALE" 'BEGIN { v = int(a * s + 0.5); print v < 1 ? 1 : v }'; }
I=$W/in
mkdir -p "$I"
make_inputs() {
    cd "$I" || return 1
    # the box of the end-to-end tests with two suns (test/e2e/lib.sh)
    (HD_TEST_TMP=$W/lib; . "$ROOT/test/e2e/lib.sh" && cd "$ROOT" && roofbox_suns) > box.rad || return 1
    printf 'solar1\nsolar2\n' > mods.txt
    # floor sensors pointing up: a square grid of side n
    grid() { awk -v n="$1" 'BEGIN { for (y = 0; y < n; y++) for (x = 0; x < n; x++)
                 printf "%.6f %.6f 0.001 0 0 1\n", (x + .5) / n, (y + .5) / n }'; }
    grid "$(scaled 60)" > pts_rtrace.txt
    grid "$(scaled 70)" > pts_rcontrib.txt
    grid "$(scaled 800)" > pts_ap.txt
    mkpmap -apC a.pm 1m -apo port_m -apr 3 -n 2 box.rad > /dev/null 2>&1 || return 1
    # a year of weather, its sky matrix (MF:1) and a DC matrix of floor points
    genwea -a 41.98 -o 87.9 -m 90 > year.wea || return 1
    gendaymtx -m 1 year.wea > sky.smx 2> /dev/null || return 1
    awk -v n="$(scaled 1000)" 'BEGIN { srand(7); print "#?RADIANCE"; print "NROWS=" n; print "NCOLS=146"
            print "NCOMP=3"; print "FORMAT=ascii"; print ""
            for (r = 0; r < n; r++) { for (c = 0; c < 146; c++) { v = rand() * 1e-3; printf "%g %g %g ", v, v, v }
                                      print "" } }' > dc.mtx
    # the annual composition: synthetic sky (146) and sun (145) pictures
    local px; px=$(scaled 128)
    for k in $(seq 0 145); do
        pcomb -x "$px" -y "$px" -e "lo=1e-3*$((1 + k % 7))*(1+x/xmax);" > "sky$k.hdr" || return 1
    done
    for k in $(seq 0 144); do
        pcomb -x "$px" -y "$px" -e "lo=$((k % 11 == 5))*1e-2*(1+y/ymax);" > "sun$k.hdr" || return 1
    done
    printf -- '-vta -vp 0.5 0.5 0.001 -vd 0 0 1 -vu 0 1 0 -vh 180 -vv 180\n' > fish.vf
    cp -r "$ROOT/scenes/cfs" cfs
}
log "making the inputs (scale $SCALE)"
(PATH=$NEWBIN:$PATH make_inputs) > "$W/inputs.log" 2>&1 || { tail -20 "$W/inputs.log" >&2; exit 1; }

# ---- the benchmarks: run in an empty folder, outputs there; $1 = threads ----
bench_rtrace() { rtrace -h -I -ab 2 -ad 1024 -aa 0 -n "$1" "$I/box.rad" < "$I/pts_rtrace.txt" > out.txt; }
bench_rpict() {
    rpict -x "$(scaled 128)" -y "$(scaled 128)" -ab 2 -ad 256 -aa 0 -n "$1" -vf "$I/fish.vf" "$I/box.rad" > out.hdr
}
bench_rcontrib() { rcontrib -h -fad -I+ -ab 1 -ad 512 -n "$1" -M "$I/mods.txt" "$I/box.rad" < "$I/pts_rcontrib.txt" > out.dat; }
bench_rcontrib_ap() {
    rcontrib -h -fad -I+ -ab -1 -ap "$I/a.pm" 50 -n "$1" -M "$I/mods.txt" "$I/box.rad" < "$I/pts_ap.txt" > out.dat
}
bench_mkpmap() { mkpmap -apC out.pm "$(scaled 5000)k" -apo port_m -apr 3 -n "$1" "$I/box.rad" > /dev/null; }
bench_dctimestep() { dctimestep -n "$1" -of "$I/dc.mtx" "$I/sky.smx" > out.mtx; }
bench_genbsdf() {
    # -r '-ad 0': one path per sample, as scenes/cfs makes its XMLs (since 9707b1f the default is
    # Radiance's -ad 700, several hundred times the CPU here: 20+ min a run, and not what older builds did)
    (cd "$I/cfs" && genBSDF -n "$1" -r '-ad 0' -c "$(scaled 4000)" -t4 5 -geom millimeter -dim -50 50 -50 50 -12.01 0 \
        slat.mat cfs1.rad) > out.xml
}
bench_pmcompose() {
    pmcompose -w "$I/year.wea" -vf "$I/fish.vf" -s "$I/sun%d.hdr" -k "$I/sky%d.hdr" -o out.csv -n "$1" \
        -r "$(seq -s, 2000 $((2000 + $(scaled 1000))))"
}

# one run: "wall cpu" on stdout; outputs left in $W/run
run_once() {   # BIN NAME THREADS
    rm -rf "$W/run"; mkdir -p "$W/run"
    local t0 t1 tm
    t0=$(date +%s.%N)
    # times (a builtin, not piped: a forked copy would not see the children)
    tm=$(cd "$W/run" && PATH=$1:$PATH && { "bench_$2" "$3" 2> err.txt || echo FAILED; } && times > times.txt
         sed -n 2p times.txt; rm -f times.txt)
    t1=$(date +%s.%N)
    case $tm in *FAILED*) log "$2 -n $3 failed with $1: $(tail -3 "$W/run/err.txt")"; return 1 ;; esac
    # "0m1.234s 0m0.056s": children's user and system time
    echo "$t0 $t1 $tm" | awk '{ gsub(/[ms]/, " ", $3); gsub(/[ms]/, " ", $4); split($3, u, " "); split($4, s, " ")
        printf "%.3f %.3f\n", $2 - $1, u[1] * 60 + u[2] + s[1] * 60 + s[2] }'
}
outsum() { (cd "$W/run" && find . -type f ! -name err.txt | sort | xargs -r md5sum); }
median() { sort -g | awk '{ v[NR] = $1 } END { print NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

echo "compare_builds: new $new_id vs old $old_id ($REV); $ROUNDS rounds; judged on $METRIC, tolerance $TOL;" \
     "load at start $(cut -d' ' -f1-3 /proc/loadavg); $(date -u '+%Y-%m-%d %H:%M UTC')"
printf '%-12s %3s | %9s %9s %6s | %9s %9s %6s | %-4s | %s\n' benchmark -n "old wall" "new wall" ratio \
    "old cpu" "new cpu" ratio "" outputs
fails=0
for b in $BENCHES; do
    for n in $NLIST; do
        : > "$W/t.old"; : > "$W/t.new"; same=same; ok=1
        for r in $(seq 1 "$ROUNDS"); do
            if [ $((r % 2)) = 1 ]; then order="old new"; else order="new old"; fi
            for side in $order; do
                if [ $side = old ]; then bin=$OLDBIN; else bin=$NEWBIN; fi
                run_once "$bin" "$b" "$n" >> "$W/t.$side" || { ok=0; break 2; }
                [ "$r" = 1 ] && outsum > "$W/sum.$side"
            done
        done
        if [ $ok = 0 ]; then printf '%-12s %3s | failed\n' "$b" "$n"; fails=$((fails + 1)); continue; fi
        cmp -s "$W/sum.old" "$W/sum.new" || same=differ
        ow=$(cut -d' ' -f1 "$W/t.old" | median); nw=$(cut -d' ' -f1 "$W/t.new" | median)
        oc=$(cut -d' ' -f2 "$W/t.old" | median); nc=$(cut -d' ' -f2 "$W/t.new" | median)
        awk -v b="$b" -v n="$n" -v ow="$ow" -v nw="$nw" -v oc="$oc" -v nc="$nc" -v m="$METRIC" -v tol="$TOL" \
            -v same="$same" 'BEGIN { rw = ow > 0 ? nw / ow : 1; rc = oc > 0 ? nc / oc : 1; r = m == "cpu" ? rc : rw
                verdict = r <= 1 + tol ? "PASS" : "FAIL"
                printf "%-12s %3s | %8.2fs %8.2fs %6.3f | %8.2fs %8.2fs %6.3f | %-4s | %s\n", b, n, ow, nw, rw, oc, nc, rc, verdict, same
                exit verdict == "FAIL" }' || fails=$((fails + 1))
    done
done
echo "compare_builds: load at end $(cut -d' ' -f1-3 /proc/loadavg); $fails benchmark(s) failed or slower than $TOL"
[ "$fails" = 0 ]
