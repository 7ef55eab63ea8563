#!/bin/sh
# rcollate's output header comes from the one header writer (hd_header_put): the input
# header's lines, the command line, NCOMP, NROWS, NCOLS and a FORMAT line padded for binary
# data as Radiance's rcollate pads it in a file, so that floats start at a multiple of 4 bytes
# and doubles of 8; the records themselves are moved, not changed.
. test/e2e/lib.sh

# 2 rows x 3 columns of RGB floats 0..17, no header (-hi), transposed to 3 x 2
awk 'BEGIN { for (i = 0; i < 18; i++) print i }' | rcalc -of -e '$1=$1' > "$T/in.f"
if [ "$(wc -c < "$T/in.f")" -ne 72 ]; then fail rcollate_input "rcalc wrote $(wc -c < "$T/in.f") bytes"; exit 0; fi
rcollate -hi -ff3 -ir 2 -ic 3 -t "$T/in.f" > "$T/t.f"
hb=$(( $(wc -c < "$T/t.f") - 72 ))
vars=$(getinfo < "$T/t.f" | grep -vE '^(#\?|$)' | sed 's/ *$//' | tr '\n' '|')
want='rcollate -hi -ff3 -ir 2 -ic 3 -t|NCOMP=3|NROWS=3|NCOLS=2|FORMAT=float|'
if [ "$vars" = "$want" ] && [ $((hb % 4)) -eq 0 ]; then pass rcollate_header_float
else fail rcollate_header_float "header '$vars' ($hb bytes; want '$want', a multiple of 4)"; fi
# transposed records: row r, column c of the output is record c*3+r of the input
tail -c 72 "$T/t.f" | rcalc -if3 -oa -e '$1=$1;$2=$2;$3=$3' > "$T/t.txt"
if [ "$(awk '{printf "%s ", $1}' "$T/t.txt")" = "0 9 3 12 6 15 " ]; then pass rcollate_transpose_float
else fail rcollate_transpose_float "$(tr '\n' ' ' < "$T/t.txt")"; fi
# doubles: the input header's lines are kept, FORMAT padded to 8
{ printf '#?RADIANCE\nmade by hand\nNROWS=2\nNCOLS=3\nNCOMP=3\nFORMAT=double\n\n'
  awk 'BEGIN { for (i = 0; i < 18; i++) print i }' | rcalc -od -e '$1=$1'; } > "$T/in.d"
rcollate -t "$T/in.d" > "$T/t.d"
hb=$(( $(wc -c < "$T/t.d") - 144 ))
vars=$(getinfo < "$T/t.d" | grep -vE '^(#\?|$)' | sed 's/ *$//' | tr '\n' '|')
want='made by hand|rcollate -t|NCOMP=3|NROWS=3|NCOLS=2|FORMAT=double|'
if [ "$vars" = "$want" ] && [ $((hb % 8)) -eq 0 ]; then pass rcollate_header_double
else fail rcollate_header_double "header '$vars' ($hb bytes; want '$want', a multiple of 8)"; fi
