# pfilt -t lamp / -f table: colour balance for a lamp type from a lamp table
# (Radiance's lamp.tab format; heliodon's own lib/lamp.tab by default).
# Values are checked against what the table says (a grey lamp of
# depreciation m multiplies the exposure by 1/m; aliases and first-match
# order), the output pixels against the exposure, and the errors.
. test/e2e/lib.sh
pcomb -x 8 -y 4 -e 'ro=.2;go=.4;bo=.1' > "$T/in.hdr" || { fail setup "pcomb"; exit 0; }
cat > "$T/lamps.tab" <<'TAB'
# test table
/grey half/		.3333333 .3333333 .5
/grey/			.3333333 .3333333 .25
/alias\>.*\<half/	(grey half)
%bar/slash%		.3333333 .3333333 .8
/sodium/		.5752 .4242 .93
TAB
expo() { getinfo < "$1" | awk -F= '/^EXPOSURE=/ { e = $2 } END { print e + 0 }'; }
pfilt -1 -f "$T/lamps.tab" -t "Grey Half lamp" "$T/in.hdr" > "$T/half.hdr"
e=$(expo "$T/half.hdr")
close "$e" 2 1e-4 && pass grey_lamp_exposure || fail grey_lamp_exposure "EXPOSURE=$e (expected 2: 1/m, m = .5)"
v=$(pvalue -h -H "$T/half.hdr" | awk 'NR == 1 { print $3, $4, $5 }')
[ "$(echo "$v" | awk '{ print ($1 > .39 && $1 < .41 && $2 > .79 && $2 < .81 && $3 > .19 && $3 < .21) }')" = 1 ] &&
    pass grey_lamp_pixels || fail grey_lamp_pixels "$v (expected .4 .8 .2)"
pfilt -1 -f "$T/lamps.tab" -t "grey" "$T/in.hdr" > "$T/q.hdr"
close "$(expo "$T/q.hdr")" 4 1e-4 && pass first_match || fail first_match "EXPOSURE=$(expo "$T/q.hdr") (expected 4)"
pfilt -1 -f "$T/lamps.tab" -t "alias to half" "$T/in.hdr" > "$T/a.hdr"
close "$(expo "$T/a.hdr")" 2 1e-4 && pass alias || fail alias "EXPOSURE=$(expo "$T/a.hdr")"
pfilt -1 -f "$T/lamps.tab" -t "a bar/slash lamp" "$T/in.hdr" > "$T/p.hdr"
close "$(expo "$T/p.hdr")" 1.25 1e-4 && pass other_delimiter || fail other_delimiter "EXPOSURE=$(expo "$T/p.hdr")"
# a lamp outside the RGB gamut: every channel still finite and positive
pfilt -1 -f "$T/lamps.tab" -t sodium "$T/in.hdr" > "$T/s.hdr"
cc=$(getinfo < "$T/s.hdr" | awk '/^COLORCORR=/ { print $2, $3, $4 }')
[ "$(echo "$cc" | awk 'NF == 3 && $1 > 0 && $2 > 0 && $3 > 0 && $1 < $2 { print 1 }')" = 1 ] &&
    pass sodium_colorcorr || fail sodium_colorcorr "COLORCORR='$cc' (expected 3 positive factors, red < green)"
# heliodon's own table is found without -f
pfilt -1 -t "cool white" "$T/in.hdr" > "$T/cw.hdr" 2> "$T/cw.err" && getinfo < "$T/cw.hdr" | grep -q '^COLORCORR=' &&
    pass default_table || fail default_table "$(cat "$T/cw.err")"
check_fails unknown_lamp "nosuch: unknown lamp type" pfilt -1 -f "$T/lamps.tab" -t nosuch "$T/in.hdr"
printf '/ok/ .3 .3 1\n/broken .3 .3 1\n' > "$T/bad1.tab"
check_fails unclosed_pattern "bad1.tab, line 2: unclosed pattern" pfilt -1 -f "$T/bad1.tab" -t x "$T/in.hdr"
printf '/ok/ .3 .3\n' > "$T/bad2.tab"
check_fails bad_lamp_data "bad2.tab, line 1: expected" pfilt -1 -f "$T/bad2.tab" -t ok "$T/in.hdr"
printf '/a/ (nothing)\n' > "$T/bad3.tab"
check_fails unmatched_alias "unmatched alias 'nothing'" pfilt -1 -f "$T/bad3.tab" -t a "$T/in.hdr"
check_fails missing_table "cannot find lamp table" pfilt -1 -f "$T/none.tab" -t a "$T/in.hdr"
