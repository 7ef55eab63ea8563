#!/bin/bash
# A pipeline run killed in its longest stage (the refined sun DC of the glare view's window pixels,
# rcontrib writing into desk/dcfensun.tmp) and started again continues from its finished stages
# and ends with the same annual CSV, sensor illuminance and hour logs as an uninterrupted run:
# no stage output exists under its final name before it is complete (temp + rename), finished
# stages are not run again (timings), and the results are identical byte for byte.
. test/e2e/lib.sh
ROOT=$(pwd)
T=$(cd "$T" && pwd)
C=$ROOT/scenes/corner
printf '%s\n' "place Berlin_e2e" "latitude 52.5" "longitude -13.4" "time_zone -15" "site_elevation 40" \
    "weather_data_file_units 1" "3 21 6.5 24 27" "3 21 8.5 559 106" "3 21 10.5 745 124" "3 21 12.5 776 129" \
    "3 21 14.5 717 120" "3 21 16.5 522 78" "3 21 20.5 0 0" > "$T/w.wea"
ARGS=(WEATHER="$T/w.wea" RES=32 MF=1 PHOTONS=50k NPROC=2 MAT_east_high="$ROOT/scenes/cfs/cfs1_klems.xml"
      SKY_OPTS="-ab 2 -ad 128 -lw 1e-3" FEN_OPTS="-ab 2 -ad 128 -lw 1e-3" FENSUN_OPTS="-ab 2 -ad 256 -lw 1e-4" FENSUN_C=8
      SENSOR_SUN_OPTS="-ab 2 -ad 128 -lw 1e-3" SENSOR_SKY_OPTS="-ab 2 -ad 128 -lw 1e-3")
if ! make -s -C "$C" OUT="$T/b" "${ARGS[@]}" > "$T/b.log" 2>&1; then
    fail uninterrupted_run "$(grep -v 'no emission\|no photons stored' "$T/b.log" | tail -3 | tr '\n' ' ')"; exit 0
fi
pass uninterrupted_run
# the same run, killed while rcontrib writes the refined sun DC of view desk
setsid make -s -C "$C" OUT="$T/a" "${ARGS[@]}" > "$T/a1.log" 2>&1 &
pid=$!
for _ in $(seq 1 600); do
    [ -d "$T/a/desk/dcfensun.tmp" ] && ls "$T/a/desk/dcfensun.tmp" > /dev/null 2>&1 && break
    kill -0 $pid 2> /dev/null || break
    sleep 0.1
done
sleep 0.3
if kill -0 $pid 2> /dev/null && [ -d "$T/a/desk/dcfensun.tmp" ]; then
    kill -TERM -- -$pid 2> /dev/null; wait $pid 2> /dev/null
    pass killed_in_stage
else
    wait $pid 2> /dev/null
    fail killed_in_stage "the run ended before the refined sun DC stage could be interrupted"; exit 0
fi
if [ ! -e "$T/a/desk/dcfensun" ] && [ ! -e "$T/a/desk/annual.csv" ] && [ ! -e "$T/a/desk/annual.done" ]; then pass nothing_final
else fail nothing_final "a final output of an unfinished stage exists: $(ls "$T/a/desk" | tr '\n' ' ')"; fi
ndone=$(wc -l < "$T/a/timings.txt")
if ! make -s -C "$C" OUT="$T/a" "${ARGS[@]}" > "$T/a2.log" 2>&1; then
    fail resumed_run "$(grep -v 'no emission\|no photons stored' "$T/a2.log" | tail -3 | tr '\n' ' ')"; exit 0
fi
pass resumed_run
# the stages finished before the kill ran once
if [ "$(grep -c '^gensuns ' "$T/a/timings.txt")" = 1 ] && [ "$(grep -c '^mkpmap ' "$T/a/timings.txt")" = 1 ] &&
   [ "$(grep -c '^rcontrib_fensun_desk ' "$T/a/timings.txt")" = 1 ] && [ "$ndone" -ge 3 ]; then pass resumed_not_redone
else fail resumed_not_redone "timings: $(awk '{print $1}' "$T/a/timings.txt" | tr '\n' ' ')"; fi
# every stage line: NAME WALL cpu CPU rss_mb RSS disk_mb DISK peak_mb PEAK (pipeline/stage.sh) with sane
# values: CPU and RSS positive (RSS from GNU time when there), the photon map's stage added the map's
# size (du, 4 KiB blocks), and no stage saw the run folder larger than its peak
bad=$(awk '!(NF == 10 && $3 == "cpu" && $5 == "rss_mb" && $7 == "disk_mb" && $9 == "peak_mb" && $2 >= 0 && $4 >= 0 &&
             ($6 == "-" || ($6 > 0.5 && $6 < 8000)) && $10 >= 0 && $10 >= $8) {print NR ": " $0; exit}' "$T/a/timings.txt" "$T/b/timings.txt")
if [ -z "$bad" ]; then pass timings_columns; else fail timings_columns "$bad"; fi
cpm=$(wc -c < "$T/b/sun.cpm")
if awk -v c="$cpm" '$1 == "mkpmap" {d = $8 - c / 1e6; ok = (d < 0 ? -d : d) <= 0.1 + 0.1 * c / 1e6; rss = $6}
        $1 ~ /^rcontrib_sun_/ && $4 > 0 {sun = 1} END {exit !(ok && sun && (rss == "-" || rss > 1))}' "$T/b/timings.txt"
then pass timings_disk_rss
else fail timings_disk_rss "sun.cpm $cpm bytes; $(grep '^mkpmap ' "$T/b/timings.txt")"; fi
if /usr/bin/time -o /dev/null -f %M true 2> /dev/null; then
    if awk '$6 == "-" {exit 1}' "$T/b/timings.txt"; then pass timings_rss_measured
    else fail timings_rss_measured "a stage without RSS: $(grep ' rss_mb - ' "$T/b/timings.txt" | head -1)"; fi
else skip timings_rss_measured "no GNU time"; fi
for f in desk/annual.csv desk/hours.log corner/hours.log grid/illuminance.csv grid/metrics.csv; do
    if cmp -s "$T/a/$f" "$T/b/$f"; then pass "identical_$(echo "$f" | tr '/.' '__')"
    else fail "identical_$(echo "$f" | tr '/.' '__')" "$T/a/$f differs from the uninterrupted run"; fi
done
# no temporary leftovers after the resumed run
left=$(find "$T/a" -name '*.tmp' -o -name '*.tmp.cpm' | head -3)
if [ -z "$left" ]; then pass no_temporaries; else fail no_temporaries "$left"; fi
