#!/bin/sh
# gendaymtx against Radiance 6.1 references (../shared/ref/sky/daymtx):
# every element within 0.5 % where it exceeds 1e-3 of its column maximum
# (plus the %.3g rounding for ascii references), column sums within 0.1 %.
. test/e2e/lib.sh
S=$REF/sky
if ! have_ref sky/daymtx; then skip all "no reference folder $S"; exit 0; fi

# data of a matrix file as one "r g b" triple per line (header removed)
triples() { # file
    case $1 in *.gz) gzip -dc "$1" ;; *) cat "$1" ;; esac > "$T/raw"
    nr=$(grep -a -m1 '^NROWS=' "$T/raw" | cut -d= -f2); nc=$(grep -a -m1 '^NCOLS=' "$T/raw" | cut -d= -f2)
    if grep -a -q '^FORMAT=ascii' "$T/raw"; then
        sed '1,/^$/d' "$T/raw" | awk 'NF==3'
    elif grep -a -q '^FORMAT=double' "$T/raw"; then
        tail -c $((nr * nc * 24)) "$T/raw" | od -An -v -t f8 -w24
    else
        tail -c $((nr * nc * 12)) "$T/raw" | od -An -v -t f4 -w12
    fi
}
# compare NAME OURS REF (ascii references: plus one unit of the 3rd digit)
compare() {
    n=$1; ours=$2; ref=$3
    nc=$(grep -a -m1 '^NCOLS=' "$ref" 2>/dev/null | cut -d= -f2)
    [ -n "$nc" ] || nc=$(gzip -dc "$ref" | grep -a -m1 '^NCOLS=' | cut -d= -f2)
    asc=0; case $ref in *.gz) ;; *) grep -a -q '^FORMAT=ascii' "$ref" && asc=1 ;; esac
    triples "$ours" > "$T/a"; triples "$ref" > "$T/b"
    if [ "$(wc -l < "$T/a")" != "$(wc -l < "$T/b")" ]; then fail "$n" "sizes differ"; return; fi
    paste "$T/a" "$T/b" | awk -v nc="$nc" -v asc="$asc" '
        { c = (NR - 1) % nc; for (k = 1; k <= 3; k++) { a[NR,k] = $k; b[NR,k] = $(k+3);
              if ($(k+3) > mx[c,k]) mx[c,k] = $(k+3); sa[c,k] += $k; sb[c,k] += $(k+3) } }
        END { bad = 0; worst = 0
            for (i = 1; i <= NR; i++) { c = (i - 1) % nc
                for (k = 1; k <= 3; k++) { x = a[i,k]; y = b[i,k]; d = x - y; if (d < 0) d = -d
                    tol = 0.005 * y; if (asc && y > 0) { e = log(y) / log(10); f = int(e); if (f > e) f--; tol += 10^(f - 2) }
                    if (y > 1e-3 * mx[c,k]) { if (d > tol) bad++; if (y > 0 && d / y > worst) worst = d / y }
                    else if (d > 1e-3 * mx[c,k] + 1e-6) bad++ } }
            sw = 0
            for (c = 0; c < nc; c++) for (k = 1; k <= 3; k++) if (sb[c,k] > 0) {
                d = sa[c,k] - sb[c,k]; if (d < 0) d = -d; if (d / sb[c,k] > sw) sw = d / sb[c,k] }
            printf "worst element %.4f%%, worst column sum %.4f%%, %d outside\n", 100*worst, 100*sw, bad
            exit !(bad == 0 && (asc || sw <= 0.001)) }' > "$T/cmp.out"
    if [ $? -eq 0 ]; then pass "$n ($(cat "$T/cmp.out"))"; else fail "$n" "$(cat "$T/cmp.out")"; fi
}

run() { # name ref-file gendaymtx-args...
    n=$1; r=$2; shift 2
    if (cd "$S" && gendaymtx "$@") > "$T/$n.mtx" 2> "$T/$n.err"; then compare "$n" "$T/$n.mtx" "$S/daymtx/$r"
    else fail "$n" "gendaymtx failed: $(head -2 "$T/$n.err")"; fi
}
for s in chicago mannheim; do
    run ${s}_sel_mf1_ascii ${s}_sel_mf1.mtx wea/${s}_sel.wea
    run ${s}_sel_mf4 ${s}_sel_mf4.mtx -m 4 -of wea/${s}_sel.wea
    run ${s}_sel_mf6 ${s}_sel_mf6.mtx -m 6 -of wea/${s}_sel.wea
    run ${s}_week_mf1 ${s}_0101-0107_mf1.mtx -of wea/${s}_0101-0107.wea
    run ${s}_week_d ${s}_0101-0107_mf1_d.mtx -d -of wea/${s}_0101-0107.wea
    run ${s}_week_s ${s}_0101-0107_mf1_s.mtx -s -of wea/${s}_0101-0107.wea
    run ${s}_week_O1 ${s}_0101-0107_mf1_O1.mtx -O1 -of wea/${s}_0101-0107.wea
    run ${s}_avg_epw ${s}_year_mf1_avg_epw.mtx -A ../weather/${s}.epw
    run ${s}_avg_wea ${s}_year_mf1_avg_wea.mtx -A wea/${s}.wea
done
run chicago_week_r30 chicago_0101-0107_mf1_r30.mtx -r 30 -of wea/chicago_0101-0107.wea
run mannheim_week_rz mannheim_0101-0107_mf1_rz-15.5.mtx -rz -15.5 -of wea/mannheim_0101-0107.wea
# (the full-year, MF:4-week and -5 MF:6 references are compared in
# test/unit/test_sky.c, which is much faster than awk)

# headers: same lines as Radiance (trailing blanks of FORMAT= ignored)
hdr() { sed -n '1,/^$/p' "$1" | sed 's/ *$//'; }
for f in chicago_sel_mf1:chicago_sel_mf1_ascii mannheim_sel_mf4:mannheim_sel_mf4 chicago_year_mf1_avg_epw:chicago_avg_epw; do
    r=${f%%:*}; o=${f#*:}
    if [ "$(hdr "$S/daymtx/$r.mtx")" = "$(hdr "$T/$o.mtx")" ]; then pass "header_$o"; else fail "header_$o" "$(hdr "$T/$o.mtx" | tr '\n' '|')"; fi
done
# sun descriptions (-D -) and modifier lists (-M): byte-identical
for s in chicago_sel mannheim_0101-0107; do
    AT=$(cd "$T" && pwd)
    (cd "$S" && gendaymtx -D - -M "$AT/$s.mods" wea/$s.wea) > "$T/$s.rad" 2>"$T/$s.err"
    # line 3 holds the command line, which names the -M file
    sed 3d "$T/$s.rad" > "$T/a.rad"; sed 3d "$S/daymtx/${s}_suns.rad" > "$T/b.rad"
    if cmp -s "$T/a.rad" "$T/b.rad" && cmp -s "$T/$s.mods" "$S/daymtx/${s}_suns.mods"; then pass "suns_$s"
    else fail "suns_$s" "differs from $S/daymtx/${s}_suns.rad / .mods"; fi
done
# warnings for bright hours with the sun below the horizon (MANIFEST item 5/13)
(cd "$S" && gendaymtx -A ../weather/chicago.epw) > /dev/null 2> "$T/warn.err"
if cmp -s "$T/warn.err" "$S/daymtx/chicago_year_mf1_avg_epw.mtx.stderr.txt"; then pass warnings_chicago
else fail warnings_chicago "stderr differs: $(diff "$T/warn.err" "$S/daymtx/chicago_year_mf1_avg_epw.mtx.stderr.txt" | head -3 | tr '\n' ' ')"; fi

# bad inputs: clear message naming file and line, non-zero exit
printf 'place X\nlatitude 40\nlongitude 0\ntime_zone 0\nsite_elevation 0\nweather_data_file_units 1\n1 1 0.5 0\n' > "$T/missing.wea"
check_fails bad_missing_column 'missing.wea: line 7: missing column 5' gendaymtx "$T/missing.wea"
printf 'place X\nlatitude 40\nlongitude 0\ntime_zone 0\nsite_elevation 0\nweather_data_file_units 1\n1 1 0.5 0 0\n1 1 1.5 abc 0\n' > "$T/nonnum.wea"
check_fails bad_non_numeric 'nonnum.wea: line 8: column 4.*abc' gendaymtx "$T/nonnum.wea"
printf 'place X\nlatitude 40\nlongitude 0\ntime_zone 0\nsite_elevation 0\nweather_data_file_units 1\n1 1 25.5 0 0\n' > "$T/hour.wea"
check_fails bad_hour 'hour.wea: line 7: hour 25.5 out of range' gendaymtx "$T/hour.wea"
printf 'plaice X\nlatitude 40\n' > "$T/header.wea"
check_fails bad_header 'header.wea: line 1: wrong header' gendaymtx "$T/header.wea"
printf 'place X\nlatitude 40\nlongitud 0\n' > "$T/header2.wea"
check_fails bad_header_keyword "header2.wea: line 3: wrong WEA header: expected 'longitude" gendaymtx "$T/header2.wea"
head -8 "$REF/weather/chicago.epw" > "$T/short.epw"; echo '1986,1,1,1,0,?9,-12.2,-16.1,73,99500,0,0,218,0,0' >> "$T/short.epw"
check_fails bad_epw_fields 'short.epw: line 9: EPW record has 15 fields' gendaymtx "$T/short.epw"
head -9 "$REF/weather/chicago.epw" | sed '9s/^1986,1,1,1,/1986,1,1,27,/' > "$T/hour.epw"
check_fails bad_epw_hour 'hour.epw: line 9: hour 27 out of range' gendaymtx "$T/hour.epw"
sed '2d' "$REF/weather/chicago.epw" | head -9 > "$T/hdr.epw"
check_fails bad_epw_header "hdr.epw: line 2: wrong EPW header: expected 'DESIGN CONDITIONS" gendaymtx "$T/hdr.epw"
check_fails bad_file 'nonexistent' gendaymtx "$T/nonexistent.wea"
check_fails bad_mf 'subdivision' gendaymtx -m 0 "$S/wea/chicago_sel.wea"
check_fails bad_5 'missing|expects' gendaymtx -5

# -u keeps exactly the steps whose sun is in the sky (the -D criterion)
n_u=$(gendaymtx -u "$S/wea/chicago_0101-0107.wea" | sed -n 's/^NCOLS=//p')
n_d=$(wc -l < "$S/daymtx/chicago_0101-0107_suns.mods")
[ "$n_u" = "$n_d" ] && pass "u_daylight_steps ($n_u)" || fail u_daylight_steps "-u gave $n_u columns, $n_d suns listed"
# same output whatever the thread count; -h drops the header; -od doubles
gendaymtx -m 2 -of -nt 1 "$S/wea/mannheim_0101-0107.wea" > "$T/nt1.mtx"
gendaymtx -m 2 -of -nt 2 "$S/wea/mannheim_0101-0107.wea" > "$T/nt2.mtx"
sed 2d "$T/nt1.mtx" > "$T/nt1b"; sed 2d "$T/nt2.mtx" > "$T/nt2b"   # line 2: command line
check threads_deterministic cmp "$T/nt1b" "$T/nt2b"
gendaymtx -h -of "$S/wea/chicago_sel.wea" > "$T/noh.mtx"
[ "$(wc -c < "$T/noh.mtx")" = $((146 * 11 * 12)) ] && pass no_header || fail no_header "$(wc -c < "$T/noh.mtx") bytes"
gendaymtx -od "$S/wea/chicago_sel.wea" > "$T/d.mtx"
if grep -aq '^FORMAT=double' "$T/d.mtx" && [ $(( $(wc -c < "$T/d.mtx") % 8 )) = 0 ]; then pass double_output; else fail double_output "bad double output"; fi
# the matrices are read back by the formats module (rmtxop), if present
if command -v rmtxop > /dev/null 2>&1; then
    if rmtxop -fa "$T/nt1.mtx" > "$T/back.txt" 2> "$T/back.err" && grep -q '^NROWS=578' "$T/back.txt"; then pass rmtxop_reads_output
    else fail rmtxop_reads_output "$(head -2 "$T/back.err")"; fi
fi
# garbage input never crashes
head -c 3000 /dev/urandom > "$T/garbage.wea" 2>/dev/null
check_fails garbage_input 'garbage.wea: line 1' gendaymtx "$T/garbage.wea"
printf 'place X\nlatitude 40\nlongitude 0\ntime_zone 0\nsite_elevation 0\nweather_data_file_units 1\n' > "$T/empty.wea"
check_fails no_records 'no weather records' gendaymtx "$T/empty.wea"
