#!/bin/sh
# genwea (synthetic weather year) and epw2wea end to end.
. test/e2e/lib.sh
genwea -a 38.4 -o -27.1 -m -30 -n Izmir > "$T/a.wea" 2> "$T/err" || fail genwea_runs "$(cat "$T/err")"
genwea -a 38.4 -o -27.1 -m -30 -n Izmir "$T/b.wea"
genwea -a 38.4 -o -27.1 -m -30 -n Izmir -s 7 > "$T/c.wea"
check genwea_deterministic cmp "$T/a.wea" "$T/b.wea"
if cmp -s "$T/a.wea" "$T/c.wea"; then fail genwea_seed "seed 7 gave the same year"; else pass genwea_seed; fi
if head -1 "$T/a.wea" | grep -q '^place SYNTHETIC_genwea_seed1_Izmir$'; then pass genwea_labelled; else fail genwea_labelled "$(head -1 "$T/a.wea")"; fi
[ "$(sed 1,6d "$T/a.wea" | wc -l)" -eq 8760 ] && pass genwea_8760 || fail genwea_8760 "$(sed 1,6d "$T/a.wea" | wc -l) records"
# the file drives gendaymtx: annual average sky, 8760 steps
if gendaymtx -A "$T/a.wea" > "$T/avg.mtx" 2> "$T/err" && grep -q '^NAVERAGED=8760$' "$T/avg.mtx" &&
    grep -q '^LATLONG= 38.40000000 27.10000000$' "$T/avg.mtx"; then pass genwea_gendaymtx
else fail genwea_gendaymtx "$(head -3 "$T/err")"; fi
check_fails genwea_missing_site 'a, -o and -m are required' genwea -a 38.4
check_fails genwea_bad_lat 'latitude out of range' genwea -a 98 -o 0 -m 0
check_fails genwea_bad_cloud 'probability out of range' genwea -a 38 -o 0 -m 0 -c 2

# epw2wea: byte-identical to Radiance's on both reference EPW files
S=$REF/sky
if have_ref sky/wea; then
    for s in chicago mannheim; do
        if epw2wea "$REF/weather/$s.epw" "$T/$s.wea" && cmp -s "$T/$s.wea" "$S/wea/$s.wea"; then pass "epw2wea_$s"
        else fail "epw2wea_$s" "differs from $S/wea/$s.wea"; fi
    done
else
    skip epw2wea_reference "no reference folder"
fi
check_fails epw2wea_wea_input 'not an EPW file' epw2wea "$T/a.wea"
printf 'LOCATION,X,,Y,z,0,40,10,1,0\nDESIGN CONDITIONS,0\n' > "$T/short.epw"
check_fails epw2wea_truncated "short.epw: line 3: unexpected end of file in the EPW header" epw2wea "$T/short.epw"
[ -e "$T/never.wea" ] && fail epw2wea_no_partial_output "left a file" || pass epw2wea_no_partial_output
epw2wea "$T/short.epw" "$T/never.wea" 2>/dev/null
[ -e "$T/never.wea" ] && fail epw2wea_no_output_on_error "left a file" || pass epw2wea_no_output_on_error
