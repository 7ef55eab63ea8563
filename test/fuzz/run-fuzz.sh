#!/bin/sh
# make fuzz: seed the corpora and run each libFuzzer harness (docs/fuzz.md).
#   test/fuzz/run-fuzz.sh [NAME...]     (default: every harness)
# Environment: FUZZ_SECONDS (per harness, default 20), BUILD (the normal
# build whose programs make seed files, default build), HELIODON_REF
# (reference folder read for extra seeds when present, default ../shared/ref).
# Harnesses run one at a time under nice.  Output in build-fuzz/: corpus/NAME
# (grown corpus), crashes/NAME (crash, leak, timeout and oom inputs),
# logs/NAME.log, and summary.tsv (executions, coverage, findings per harness).
# Exit status 1 when any harness found something.
set -u
BUILD=${BUILD:-build}
FUZZ_SECONDS=${FUZZ_SECONDS:-20}
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
printf 'harness\tseconds\texecutions\texec/s\tcov\tft\tcorpus\tfindings\n' > "$F/summary.tsv"
for n in $names; do
    bin=$F/bin/fuzz_$n
    [ -x "$bin" ] || { echo "run-fuzz: no harness $bin" >&2; status=1; continue; }
    seed "$n"
    mkdir -p "$F/corpus/$n" "$F/crashes/$n"
    echo "== fuzz_$n: $FUZZ_SECONDS s, seeds $(ls "$F/seeds/$n" | wc -l), corpus $(ls "$F/corpus/$n" | wc -l)"
    dict=; [ -f "test/fuzz/dict/$n.dict" ] && dict=-dict=test/fuzz/dict/$n.dict
    maxlen=16384; [ "$n" = pmap ] && maxlen=65536
    nice -n 10 "$bin" -max_total_time="$FUZZ_SECONDS" -timeout=10 -rss_limit_mb=2048 -max_len=$maxlen $dict \
        -print_final_stats=1 \
        -artifact_prefix="$F/crashes/$n/" "$F/corpus/$n" "$F/seeds/$n" > "$F/logs/$n.log" 2>&1
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$F/logs/$n.log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$F/logs/$n.log" | tail -1)
    last=$(grep -E '^#[0-9]+.*cov: ' "$F/logs/$n.log" | tail -1)
    cov=$(echo "$last" | sed -n 's/.*cov: \([0-9]*\).*/\1/p')
    ft=$(echo "$last" | sed -n 's/.*ft: \([0-9]*\).*/\1/p')
    found=$(ls "$F/crashes/$n" | wc -l)
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$n" "$FUZZ_SECONDS" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" \
        "$(ls "$F/corpus/$n" | wc -l)" "$found" >> "$F/summary.tsv"
    if [ "$found" -gt 0 ]; then
        status=1
        echo "   found $found input(s) in $F/crashes/$n:"
        grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)' "$F/logs/$n.log" | head -5 | sed 's/^/   /'
    fi
done
echo
column -t "$F/summary.tsv" 2>/dev/null || cat "$F/summary.tsv"
[ $status -eq 0 ] || echo "make fuzz: findings in $F/crashes/ (add each to test/fuzz/regress/NAME/ once fixed)"
exit $status
