# evalglare and glarestats against Radiance's evalglare -d outputs, plus
# bad inputs.  Tolerances: DGP 0.005 and DGI 0.5 (issue 9), E_v 1e-5
# relative, UGR 0.05, source count exact.
. test/e2e/lib.sh

# cmp_line OUT REF : compare our -d last line with Radiance's
cmp_line() {
    awk -F': ' '/^dgp,av_lum/ {print $2}' "$1" > "$T/a.vals"
    awk -F': ' '/^dgp,av_lum/ {print $2}' "$2" > "$T/b.vals"
    paste -d' ' "$T/a.vals" "$T/b.vals" | awk '{
        n = NF / 2; if (n != 23) exit 1
        ddgp = $1 - $(n+1); ddgi = $6 - $(n+6); dugr = $7 - $(n+7); dev = ($3 - $(n+3)) / $(n+3)
        if (ddgp < 0) ddgp = -ddgp; if (ddgi < 0) ddgi = -ddgi; if (dugr < 0) dugr = -dugr; if (dev < 0) dev = -dev
        printf "dDGP %.2e dDGI %.2e dUGR %.2e dEv %.2e\n", ddgp, ddgi, dugr, dev
        exit !(ddgp <= 0.005 && ddgi <= 0.5 && dugr <= 0.05 && dev <= 1e-5) }'
}

n=0
for dir in "$REF/scenes/office" "$REF/scenes/box"; do
    [ -d "$dir" ] || continue
    for img in "$dir"/*.hdr; do
        ref=${img%.hdr}.evalglare.txt
        [ -f "$ref" ] || continue
        b=$(basename "$img" .hdr)
        if evalglare -vta -vv 180 -vh 180 -d -b 2000 "$img" > "$T/$b.txt" 2> "$T/$b.err"; then
            if msg=$(cmp_line "$T/$b.txt" "$ref"); then pass "ref_$b ($msg)"; else fail "ref_$b" "$msg"; fi
            ns=$(head -1 "$T/$b.txt" | awk '{print $1}'); nr=$(head -1 "$ref" | awk '{print $1}')
            if [ "$ns" = "$nr" ]; then pass "sources_$b"; else fail "sources_$b" "$ns sources, Radiance $nr"; fi
            # the default output line carries the same numbers
            evalglare -vta -vv 180 -vh 180 -b 2000 "$img" > "$T/$b.line"
            d1=$(awk '{print $2}' "$T/$b.line"); d2=$(awk -F': ' '/^dgp,av/ {split($2, v, " "); print v[1]}' "$T/$b.txt")
            if grep -q '^dgp,dgi,ugr,vcp,cgi,Lveil: ' "$T/$b.line" && [ "$d1" = "$d2" ]; then pass "line_$b"
            else fail "line_$b" "$(cat "$T/$b.line")"; fi
        else
            fail "ref_$b" "$(cat "$T/$b.err")"
        fi
        n=$((n + 1))
    done
done
[ "$n" -gt 0 ] || skip references "no evalglare references under $REF/scenes"

# view taken from the header gives the same DGP (rotation invariant)
img="$REF/scenes/box/a2_clear_fish.hdr"
if [ -f "$img" ]; then
    a=$(evalglare "$img" | awk '{print $2}')
    b=$(evalglare -vta -vh 180 -vv 180 "$img" | awk '{print $2}')
    if [ "$a" = "$b" ]; then pass header_view; else fail header_view "$a vs $b"; fi
    # -V: E_v only, equal to the E_v of -d
    ev=$(evalglare -V "$img"); evd=$(evalglare -d "$img" | awk -F': ' '/^dgp,av/ {split($2, v, " "); print v[3]}')
    if close "$ev" "$evd" 1e-9; then pass ev_only; else fail ev_only "$ev vs $evd"; fi
    # -c check picture: a valid picture of the same size
    check checkfile evalglare -c "$T/check.hdr" "$img"
    if getinfo -d "$T/check.hdr" 2>/dev/null | grep -q '256 +X *256'; then pass checkfile_size
    else fail checkfile_size "$(getinfo -d "$T/check.hdr" 2>&1)"; fi
    # bad inputs
    check_fails persp "not a fisheye" evalglare "$REF/scenes/box/a2_clear_persp.hdr"
    grep -av '^VIEW=' "$img" > "$T/noview.hdr"
    check_fails noview "no VIEW= line" evalglare "$T/noview.hdr"
    check_fails partialview "must contain at least -vt" evalglare -vta "$T/noview.hdr"
    head -c 100000 "$img" > "$T/trunc.hdr"
    check_fails truncated "unexpected end of data" evalglare "$T/trunc.hdr"
    check_fails missing "no-such" evalglare "$T/no-such.hdr"
    check_fails unsupported "not supported" evalglare -s "$img"
    check_fails badview "unknown view type" evalglare -vtq -vh 180 -vv 180 "$img"
    # annual statistics on the same images
    ls "$REF"/scenes/office/*.hdr "$REF"/scenes/box/a2_*_fish.hdr | awk '{print NR, $0}' > "$T/list.txt"
    if glarestats -l "$T/list.txt" -o "$T/annual.csv" -S "$T/summary.txt"; then
        rows=$(($(wc -l < "$T/annual.csv") - 1)); want=$(wc -l < "$T/list.txt")
        if [ "$rows" = "$want" ] && head -1 "$T/annual.csv" | grep -q '^hour,Ev,DGP,DGI'; then pass annual_csv
        else fail annual_csv "$rows rows for $want pictures"; fi
        closed=$(awk -F, 'NR>1 && $3 >= 0.40 {n++} END {print n+0}' "$T/annual.csv")
        if grep -q "^shade_closed: $closed hours" "$T/summary.txt"; then pass annual_shade
        else fail annual_shade "expected $closed: $(grep shade "$T/summary.txt")"; fi
        grep -q '^DGP_p95: ' "$T/summary.txt" && pass annual_p95 || fail annual_p95 "no DGP_p95"
    else
        fail annual_csv "glarestats failed"
    fi
    check_fails annual_persp "not a fisheye" glarestats "$REF/scenes/box/a2_clear_persp.hdr"
    echo "1 $T/none.hdr" > "$T/badlist.txt"
    check_fails annual_missing "cannot open" glarestats -l "$T/badlist.txt"
    echo "one $img" > "$T/badlist2.txt"
    check_fails annual_badline "line 1: expected" glarestats -l "$T/badlist2.txt"
else
    skip bad_inputs "no $img"
fi
