#!/bin/sh
# make fuzz: seed the corpora and run each libFuzzer harness (docs/fuzz.md).
#   test/fuzz/run-fuzz.sh [NAME...]     (default: every harness)
# Environment: FUZZ_SECONDS (per harness, default 20; FUZZ_SECONDS_NAME for
# one harness), FUZZ_RUNS or FUZZ_RUNS_NAME (stop after that many executions
# if the time is not up first), BUILD (the normal
# build whose programs make seed files, default build), HELIODON_REF
# (reference folder read for extra seeds when present, default ../shared/ref).
# FUZZ_NICE (niceness of the fuzzer, default 10: 0 gives it a full core on a
# machine whose other work runs niced).
# Harnesses run one at a time under nice.  Output in build-fuzz/: corpus/NAME
# (grown corpus), crashes/NAME (crash, leak, timeout and oom inputs),
# logs/NAME.log and NAME.timeline (status lines with seconds and load),
# summary.tsv (executions, CPU, coverage, when cov last grew, load, plateau
# per harness) and history.tsv (the same for every run; the corpora carry
# over from run to run).
# Exit status 1 when any harness found something.
set -u
BUILD=${BUILD:-build}
FUZZ_SECONDS=${FUZZ_SECONDS:-20}
FUZZ_NICE=${FUZZ_NICE:-10}
REF=${HELIODON_REF:-../shared/ref}
F=build-fuzz
B=$BUILD/bin
names=${*:-"scene bsdf hdr matrix exr weather pmap view options"}
mkdir -p "$F/seeds" "$F/corpus" "$F/crashes" "$F/logs" "$F/tmp"
T=$F/tmp

# Files of the reference folder as extra seeds: small ones only.
ref_files() {  # pattern max_bytes
    [ -d "$REF" ] || return 0
    find "$REF" -type f -name "$1" -size -"$2"c 2>/dev/null | sort | head -40
}

seed() {  # NAME: fill $F/seeds/NAME
    d=$F/seeds/$1
    rm -rf "$d"; mkdir -p "$d"
    for s in test/fuzz/seeds/"$1"/* test/fuzz/regress/"$1"/*; do [ -f "$s" ] && cp "$s" "$d/"; done
    case $1 in
    scene)
        i=0
        for s in $(find scenes test/e2e -name '*.rad' -size -65536c | sort) $(ref_files '*.rad' 65536); do
            i=$((i + 1)); cp "$s" "$d/p$i.rad"
        done ;;
    bsdf)
        for s in $(find scenes -name '*.xml' -size -200000c | sort) $(ref_files '*.xml' 200000); do
            cp "$s" "$d/p_$(basename "$s")"
        done ;;
    hdr|exr|matrix)
        # small pictures from the project's own renderer: run-length (x >= 8)
        # and flat (x < 8) scanlines, one with a VIEW= line
        { printf 'void plastic grey 0 0 5 .5 .5 .5 0 0\nvoid light sky 0 0 3 1 1 1\n'
          printf 'sky source s 0 0 4 0 0 1 180\n'
          cat test/e2e/roofbox.rad | sed 's/^black /grey /; s/^floormat /grey /; s/^port_m /grey /'; } > "$T/box.rad"
        V="-vp .5 .5 .5 -vd 0 0 -1 -vu 0 1 0 -vh 60 -vv 60"
        "$B/rpict" $V -x 16 -y 12 -ab 0 "$T/box.rad" > "$T/rle.hdr" 2>/dev/null
        "$B/rpict" $V -vta -vh 180 -vv 180 -x 5 -y 4 -ab 0 "$T/box.rad" > "$T/flat.hdr" 2>/dev/null
        case $1 in
        hdr|matrix)
            cp "$T/rle.hdr" "$T/flat.hdr" "$d/" 2>/dev/null
            for s in $(ref_files '*.hdr' 20000); do cp "$s" "$d/p_$(basename "$s")"; done ;;
        exr)
            for c in none rle zips zip piz; do
                "$B/hdr2exr" -c $c "$T/rle.hdr" "$d/rle_$c.exr" 2>/dev/null
            done
            "$B/hdr2exr" "$T/flat.hdr" "$d/flat.exr" 2>/dev/null
            for s in $(ref_files '*.exr' 40000); do cp "$s" "$d/p_$(basename "$s")"; done ;;
        esac
        if [ "$1" = matrix ]; then
            for s in $(ref_files '*.mtx' 20000) $(ref_files '*.dmx' 20000); do cp "$s" "$d/p_$(basename "$s")"; done
        fi ;;
    weather)
        "$B/genwea" -a 38.4 -o -27.1 -m -30 -n fuzz 2>/dev/null | head -60 > "$d/genwea.wea"
        for s in $(ref_files '*.wea' 10000000) $(ref_files '*.epw' 10000000); do
            head -60 "$s" > "$d/p_$(basename "$s")"
        done ;;
    view)
        for s in $(find scenes -name '*.vf' | sort) $(ref_files '*.vf' 4096); do cp "$s" "$d/p_$(basename "$s")"; done ;;
    pmap)
        { printf 'void plastic black 0 0 5 0 0 0 0 0\nvoid plastic floormat 0 0 5 .5 .5 .5 0 0\n'
          printf 'void glass port_m 0 0 3 .96 .96 .96\nvoid light solar1 0 0 3 1e6 1e6 1e6\n'
          printf 'solar1 source sun1 0 0 4 0 0 1 0.533\nvoid light solar2 0 0 3 1e6 1e6 1e6\n'
          printf 'solar2 source sun2 0 0 4 0.3 0 1 0.533\n'
          cat test/e2e/roofbox.rad; } > "$T/pbox.rad"
        "$B/mkpmap" -fo -apC "$d/small.pm" 300 -apo port_m -apZ 64 -apr 1 -n 1 "$T/pbox.rad" 2>/dev/null
        "$B/mkpmap" -fo -apC "$d/tiny.pm" 100 -apo port_m -apZ 64 -apr 2 -n 1 "$T/pbox.rad" 2>/dev/null
        # three sources whose modifier names are 120 bytes long (the longest
        # the format holds is 127)
        long=$(printf 'sun_%0116d' 0)
        { printf 'void plastic black 0 0 5 0 0 0 0 0\nvoid plastic floormat 0 0 5 .5 .5 .5 0 0\n'
          printf 'void glass port_m 0 0 3 .96 .96 .96\n'
          for k in 1 2 3; do
              printf 'void light %s%d 0 0 3 1e6 1e6 1e6\n%s%d source s%d 0 0 4 0.%d 0 1 0.533\n' \
                  "${long%?}" $k "${long%?}" $k $k $k
          done
          cat test/e2e/roofbox.rad; } > "$T/lbox.rad"
        "$B/mkpmap" -fo -apC "$d/long.pm" 150 -apo port_m -apZ 64 -apr 3 -n 1 "$T/lbox.rad" 2>/dev/null ;;
    esac
}

status=0
cols='harness\tdate\tseconds\texecutions\texec/s\tcpu_s\tcov\tft\tcorpus\tfindings\tload_min\tload_mean\tload_max\tcov_last_grew_exec\tcov_last_grew_s\tcov_half\tft_half\tplateau\n'
printf "$cols" > "$F/summary.tsv"
[ -f "$F/history.tsv" ] || printf "$cols" > "$F/history.tsv"
for n in $names; do
    bin=$F/bin/fuzz_$n
    [ -x "$bin" ] || { echo "run-fuzz: no harness $bin" >&2; status=1; continue; }
    seed "$n"
    mkdir -p "$F/corpus/$n" "$F/crashes/$n"
    # per-harness overrides: FUZZ_SECONDS_view=900 FUZZ_RUNS_view=10000000
    eval "secs=\${FUZZ_SECONDS_$n:-$FUZZ_SECONDS}"
    eval "runs=\${FUZZ_RUNS_$n:-${FUZZ_RUNS:-}}"
    runarg=; [ -n "$runs" ] && runarg=-runs=$runs
    echo "== fuzz_$n: $secs s${runs:+ or $runs runs}, seeds $(ls "$F/seeds/$n" | wc -l), corpus $(ls "$F/corpus/$n" | wc -l)"
    dict=; [ -f "test/fuzz/dict/$n.dict" ] && dict=-dict=test/fuzz/dict/$n.dict
    maxlen=16384; [ "$n" = pmap ] && maxlen=65536
    found0=$(ls "$F/crashes/$n" | wc -l)
    # The log is libFuzzer's output unchanged; the timeline has each status
    # line (#N ... cov: ... ft: ...) with the seconds since the start and the
    # 1-minute load average (sampled every 30 s) in front.
    nice -n "$FUZZ_NICE" /usr/bin/time -f '%U %S' -o "$F/logs/$n.time" \
        "$bin" -max_total_time="$secs" $runarg -timeout=10 -rss_limit_mb=2048 -max_len=$maxlen $dict \
        -print_final_stats=1 \
        -artifact_prefix="$F/crashes/$n/" "$F/corpus/$n" "$F/seeds/$n" 2>&1 |
    awk -v tl="$F/logs/$n.timeline" '
        function now() { srand(); return srand() }
        BEGIN { t0 = now(); last = -30; printf "" > tl }
        { print; fflush() }
        {   t = now() - t0
            if (t - last >= 30) { getline l < "/proc/loadavg"; close("/proc/loadavg"); split(l, a, " "); load = a[1]; last = t }
            if ($0 ~ /^#[0-9]+.*cov: /) { print t, load, $0 >> tl; fflush(tl) } }' > "$F/logs/$n.log"
    log=$F/logs/$n.log
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    cpu=$(awk '{ printf "%.0f", $1 + $2 }' "$F/logs/$n.time" 2>/dev/null)
    corpus=$(ls "$F/corpus/$n" | wc -l)
    found=$(($(ls "$F/crashes/$n" | wc -l) - found0))
    # Coverage over the run (docs/fuzz.md, "Plateau"): cov and ft at the last
    # status line, the execution and second of the last cov increase, cov and
    # ft at half the run's executions; plateau = no new cov edge and under 1 %
    # ft growth in the second half of the executions.
    stats=$(awk -v execs="${execs:-0}" '
        { n = $3; sub(/^#/, "", n); n += 0
          for (i = 4; i < NF; i++) { if ($i == "cov:") c = $(i + 1) + 0; if ($i == "ft:") f = $(i + 1) + 0 }
          if (c > cmax) { cmax = c; gexec = n; gsec = $1 }
          if (n <= execs / 2) { ch = c; fh = f }
          lc = c; lf = f; sum += $2; k++
          if (k == 1 || $2 < lmin) lmin = $2; if ($2 > lmax) lmax = $2 }
        END { if (!k) { print "? ? ? ? ? ? ? ? ? no"; exit }
              p = (lc == ch && fh > 0 && (lf - fh) < 0.01 * fh) ? "yes" : "no"
              printf "%d %d %.1f %.1f %.1f %d %d %d %d %s\n", lc, lf, lmin, sum / k, lmax, gexec, gsec, ch, fh, p }' \
        "$F/logs/$n.timeline")
    set -- $stats
    line=$(printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s' "$n" "$(date -u +%Y-%m-%dT%H:%M)" \
        "$secs" "${execs:-?}" "${rate:-?}" "${cpu:-?}" "$1" "$2" "$corpus" "$found" "$3" "$4" "$5" "$6" "$7" "$8" "$9" "${10}")
    echo "$line" >> "$F/summary.tsv"
    echo "$line" >> "$F/history.tsv"
    if [ "$found" -gt 0 ]; then
        status=1
        echo "   found $found input(s) in $F/crashes/$n:"
        grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)' "$log" | head -5 | sed 's/^/   /'
    fi
done
echo
column -t "$F/summary.tsv" 2>/dev/null || cat "$F/summary.tsv"
# executions of every run so far per harness (the corpora carry over)
awk -F'\t' 'NR > 1 { e[$1] += $4; s[$1] += $6 } END { for (h in e) printf "%s: %d executions, %d s CPU in all runs\n", h, e[h], s[h] }' \
    "$F/history.tsv" | sort
[ $status -eq 0 ] || echo "make fuzz: findings in $F/crashes/ (add each to test/fuzz/regress/NAME/ once fixed)"
exit $status
