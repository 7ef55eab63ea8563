# The annual pipeline with every DC folder in record pieces (rcontrib -R, rcmerge) and the
# composition in pieces of the daylight hours (pmcompose -H, -J): every output is byte for byte
# the whole run's (timings aside), for a view and a sensor file; pmcompose -J refuses missing,
# repeated, foreign and truncated pieces.
. test/e2e/lib.sh
T=$(cd "$T" && pwd)
export SOURCE_DATE_EPOCH=1700000000
O=$(pwd)/scenes/office
izmir_wea "$T/w.wea" '3 21 1.5 0 0' '3 21 10.5 820 110' '3 21 14.5 780 130' '12 21 12.5 60 180'
printf '%s\n' '1 2 0.8 0 0 1' '2 2 0.8 0 0 1' '3 1.5 0.8 0 0 1' '2 3 0.8 0 0 1' '1.5 1 0.8 0 0 1' > "$T/grid.pts"
ARGS=(WEATHER="$T/w.wea" CONFIG=glass VIEW=v1 RES=24 MF=1 PHOTONS=50k BANDWIDTH=50 NPROC=1 IMAGES=1
      SKY_OPTS="-ab 1 -ad 64 -lw 1e-3" FEN_OPTS="-ab 1 -ad 64 -lw 1e-3" FENSUN_OPTS="-ab 1 -ad 16 -lw 1e-3"
      SENSOR_SUN_OPTS="-ab 1 -ad 64 -lw 1e-3" SENSOR_SKY_OPTS="-ab 1 -ad 64 -lw 1e-3"
      FENSUN_C=2 GROUNDPTS=128 SENSORS="$T/grid.pts" SHADE_LIMIT=0.33)
RUN=$T/run   # both runs are made here (headers name the run folder) and moved aside
if make -s -C "$O" "${ARGS[@]}" OUT="$RUN" > "$T/whole.log" 2>&1 && mv "$RUN" "$T/whole"; then pass whole_run
else fail whole_run "$(tail -3 "$T/whole.log" | tr '\n' ' ')"; exit 0; fi
if make -s -C "$O" "${ARGS[@]}" DC_PIECES=4 HOUR_PIECES=2 OUT="$RUN" > "$T/pieces.log" 2>&1; then pass pieces_run
else fail pieces_run "$(tail -3 "$T/pieces.log" | tr '\n' ' ')"; exit 0; fi
n=$(ls -d "$RUN"/v1/*.p/3 "$RUN"/grid/*.p/3 "$RUN"/v1/compose.h/1 2>/dev/null | wc -l)
if [ "$n" -ge 6 ]; then pass made_in_pieces; else fail made_in_pieces "$n piece folders"; fi
( cd "$T/whole" && find . -type f | sort ) > "$T/f.whole"
( cd "$RUN" && find . -type f ! -path '*.p/*' ! -path '*/compose.h/*' | sort ) > "$T/f.pieces"
if cmp -s "$T/f.whole" "$T/f.pieces"; then pass same_files
else fail same_files "$(diff "$T/f.whole" "$T/f.pieces" | head -4 | tr '\n' ' ')"; fi
bad=""
while read -r f; do
    case $f in
    ./timings.txt|./report/*) continue ;;
    */summary.txt|*/notes.txt) cmp -s <(grep -v '_seconds:' "$T/whole/$f") <(grep -v '_seconds:' "$RUN/$f") || bad="$bad $f" ;;
    *) cmp -s "$T/whole/$f" "$RUN/$f" || bad="$bad $f" ;;
    esac
done < "$T/f.whole"
if [ -z "$bad" ]; then pass byte_identical; else fail byte_identical "differ:$(echo $bad | cut -c1-300)"; fi
if [ "$(ls "$RUN/v1/hourly" | wc -l)" = 3 ]; then pass hourly_images; else fail hourly_images; fi

# pmcompose -J refusals, on the pieces of the view
H=$RUN/v1/compose.h
J=(pmcompose -J -o "$T/j/annual.csv" -S "$T/j/summary.txt" -L "$T/j/hours.log")
mkdir -p "$T/j"
check_fails missing_piece "piece 1 of 2 is missing" "${J[@]}" "$H/0"
check_fails repeated_piece "both piece 0 of 2" "${J[@]}" "$H/0" "$H/0" "$H/1"
cp -r "$H/1" "$T/other"; sed -i 's/^# COMMAND= pmcompose -n 1/# COMMAND= pmcompose -n 3/' "$T/other/annual.csv" "$T/other/hours.log" "$T/other/summary.txt"
check_fails foreign_piece "not a piece of the same run" "${J[@]}" "$H/0" "$T/other"
cp -r "$H/1" "$T/trunc"; sed -i '$d' "$T/trunc/hours.log"
check_fails truncated_piece "truncated" "${J[@]}" "$H/0" "$T/trunc"
cp -r "$H/1" "$T/over"; sed -i 's/^# PIECE= 1 2 1 2 3/# PIECE= 1 2 0 2 3/' "$T/over/annual.csv" "$T/over/hours.log" "$T/over/summary.txt"
check_fails overlapping_hours "overlap" "${J[@]}" "$H/0" "$T/over"
if [ ! -e "$T/j/annual.csv" ] && [ ! -e "$T/j/hours.log" ]; then pass nothing_written; else fail nothing_written; fi
check_fails too_many_pieces "more pieces than the 3 daylight hours" make -s -C "$O" "${ARGS[@]}" HOUR_PIECES=4 OUT="$T/run4" "$T/run4/v1/compose.h/0"
