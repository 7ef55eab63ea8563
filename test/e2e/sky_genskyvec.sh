#!/bin/sh
# genskyvec (the program) against Radiance's genskyvec.pl outputs
# (../shared/ref/sky/skyvec), run on the same gendaylit/gensky descriptions.
# By default genskyvec traces Radiance's own 16 fixed pseudo-random rays per
# patch, so the issue's criteria are checked exactly: every patch value above
# 1e-3 of the maximum within 3 %, the others within 1e-3 of the maximum, the
# total within 0.5 %, plus header and layout.  The 70 reference commands of
# the manifest other than the plain -m 6 ones are run (test/unit/test_sky.c
# runs all 92 through the library, and the -ns stratified mode).
. test/e2e/lib.sh
S=$REF/sky
if ! have_ref sky/skyvec; then skip all "no reference folder $S/skyvec"; exit 0; fi
grep -o '"command": "genskyvec[^"]*"' "$S/manifest.json" | sed 's/^"command": "//; s/"$//' > "$T/cmds"
nbad=0; ntot=0; worst_all=0
while read -r cmd; do
    # the plain MF:6 vectors (22 of them) are left to test/unit/test_sky.c,
    # which runs all 92 through the library much faster
    case $cmd in "genskyvec -m 6 <"*) continue ;; esac
    args=$(echo "$cmd" | sed 's/^genskyvec //; s/ <.*//')
    in=$(echo "$cmd" | sed 's/.*< *//; s/ *>.*//')
    out=$(echo "$cmd" | sed 's/.*> *//')
    n=$(basename "$out" .vec)
    ntot=$((ntot + 1))
    # shellcheck disable=SC2086
    if ! genskyvec $args < "$S/$in" > "$T/$n.vec" 2> "$T/$n.err"; then
        fail "$n" "genskyvec failed: $(head -2 "$T/$n.err" | tr '\n' ' ')"; nbad=$((nbad + 1)); continue
    fi
    res=$(paste "$T/$n.vec" "$S/$out" | awk -F'\t' '
        /^[0-9.eE+-]+\t/ && NF == 6 { n++; for (k = 1; k <= 3; k++) { a[n,k] = $k; b[n,k] = $(k+3); if ($(k+3) > mx) mx = $(k+3); sa += $k; sb += $(k+3) } }
        END { bad = 0; w = 0
            for (i = 1; i <= n; i++) for (k = 1; k <= 3; k++) { d = a[i,k] - b[i,k]; if (d < 0) d = -d
                if (b[i,k] > 1e-3 * mx) { e = d / b[i,k]; if (e > w) w = e; if (e > 0.03) bad++; sig++ }
                else if (d > 1e-3 * mx) bad++ }
            t = sb > 0 ? (sa - sb) / sb : (sa > 0 ? 1 : 0); if (t < 0) t = -t
            printf "%d %.4f %.4f %d\n", bad, 100 * w, 100 * t, n }')
    set -- $res
    if [ "$4" = "$(sed -n 's/^NROWS=//p' "$S/$out")" ] &&
        [ "$(sed -n '2,/^$/p' "$T/$n.vec")" = "$(sed -n '2,/^$/p' "$S/$out")" ] &&
        [ "$1" -eq 0 ] && awk -v t="$3" 'BEGIN{exit !(t <= 0.5)}'; then pass "$n (worst patch $2%, total $3%)"
    else fail "$n" "$1 values outside the tolerance, worst $2%, total $3%, $4 rows"; nbad=$((nbad + 1)); fi
done < "$T/cmds"
[ "$ntot" -ge 70 ] && pass "reference_commands_run ($ntot)" || fail reference_commands_run "only $ntot"

# bad input: clear error, non-zero exit
printf 'void light solar\n0\n0\n3 1 1 1\n' > "$T/nosky.rad"
check_fails bad_no_skyfunc 'no .brightfunc skyfunc' genskyvec -m 1 < "$T/nosky.rad"
printf 'void brightfunc skyfunc\n2 skybright perezlum.cal\n0\n10 1 2 3 x 5 6 7 8 9 1\n' > "$T/badnum.rad"
check_fails bad_number 'line 4: brightfunc skyfunc: real argument 4: expected a number' genskyvec -m 1 < "$T/badnum.rad"
printf 'void brightfunc skyfunc\n2 skybright perezlum.cal\n0\n10 1 2 3\n' > "$T/short.rad"
check_fails bad_count '10 arguments announced|perezlum.cal sky needs 10' genskyvec -m 1 < "$T/short.rad"
# quirk (MANIFEST 1): -5 is a flag; "-5 .533" leaves ".533" as an argument,
# which Radiance rejects too: a clear error, non-zero exit, no output
check_fails five_takes_no_argument '\.533' genskyvec -d -m 1 -5 .533 < "$S/gendaylit/chicago_0105_1130_W.rad"
# default and -ns: Radiance's 16 rays vs the stratified integral agree
# within Radiance's sampling noise on the total (here 0.2 %)
genskyvec -m 4 < "$S/gendaylit/mannheim_0610_1230_W.rad" > "$T/r.vec"
genskyvec -m 4 -ns 8 < "$S/gendaylit/mannheim_0610_1230_W.rad" > "$T/s.vec"
ta=$(sed '1,/^$/d' "$T/r.vec" | awk '{s += $1 + $2 + $3} END {print s}')
tb=$(sed '1,/^$/d' "$T/s.vec" | awk '{s += $1 + $2 + $3} END {print s}')
if ! cmp -s "$T/r.vec" "$T/s.vec" && close "$ta" "$tb" 0.01; then pass "ns_stratified ($ta vs $tb)"
else fail ns_stratified "totals $ta vs $tb"; fi
