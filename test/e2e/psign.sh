#!/bin/bash
# psign: text drawn with a Radiance font file.
#  - a font made here (a full-cell square "A" and a blank): the coverage of
#    each pixel as the edges and parity fill give it (3 x 3 subsamples),
#    worked out by hand below;
#  - bad font files and options refused with the file, line and what was
#    expected;
#  - with Radiance's font helvet.fnt (RAYPATH, RADIANCE_LIB or
#    RADIANCE_BIN/../lib): the pictures of test/data/psign (Radiance 6.1's
#    psign, commands in MANIFEST.md there), every pixel equal.
. test/e2e/lib.sh
D=$(pwd)/test/data/psign
T=$(cd "$T" && pwd)

# ---- a font of our own: "A" the whole cell, " " blank
printf '# test font\n65 4\n 0 0 255 0 255 255 0 255\n32 0\n' > "$T/sq.fnt"
# -h 10 -a 1: cells 30 x 30 subsamples; the square's edges land on
# subsample columns 0 and 29 and cover rows 0..28, so the 10 x 10 picture
# is full (9) except its right column and top row (6 each: the 30th
# subsample column and row are outside) and the top right corner (4)
# (pvalue lists the top row as y = 9)
if psign -f "$T/sq.fnt" -h 10 -a 1 -cf 1 1 1 -cb 0 0 0 A > "$T/sq.hdr" 2> "$T/err"; then
    r=$(pvalue -h -H -o "$T/sq.hdr" | awk '{ want = 9; if ($1 == 9) want -= 3; if ($2 == 9) want -= 3; if ($1 == 9 && $2 == 9) want = 4
            v = want / 9; d = $3 - v; if (d < 0) d = -d; if (d > .004 * v + 1e-9 || $3 != $4 || $4 != $5) bad++ }
        END { printf "%d pixels, %d wrong", NR, bad; exit !(NR == 100 && bad == 0) }') && pass square_cover || fail square_cover "$r"
else fail square_cover "$(head -2 "$T/err")"; fi
# a blank between two squares (-s 0: every glyph a full cell, 255 units,
# apart; 255 * 30 >> 8 = 29 subsamples): the squares cover subsample
# columns 0..28 and 59..88, so pixels 0..8 are full below the top row and
# pixels 10..18 (the blank) empty
psign -f "$T/sq.fnt" -h 10 -a 1 -cf 1 1 1 -cb 0 0 0 'A A' > "$T/sq3.hdr" &&
    [ "$(getinfo -d < "$T/sq3.hdr" | tr -s ' ')" = "-Y 10 +X 30" ] && pass uniform_size || fail uniform_size "$(getinfo -d < "$T/sq3.hdr")"
r=$(pvalue -h -H -o "$T/sq3.hdr" | awk '$1 >= 10 && $1 <= 18 && $3 > 0 { bad++ } $1 <= 8 && $2 <= 8 && $3 < 1 { bad++ }
    END { print bad + 0; exit bad > 0 }') && pass uniform_blank || fail uniform_blank "$r pixels"

# ---- errors
printf '65 2\n 0 0 300 0\n' > "$T/bad1.fnt"
check_fails bad_coordinate "bad1.fnt: line 2: character 65: expected a coordinate 0..255" psign -f "$T/bad1.fnt" A
printf '65 0\n65 0\n' > "$T/bad2.fnt"
check_fails duplicate_glyph "bad2.fnt: line 2: character 65 defined twice" psign -f "$T/bad2.fnt" A
printf '65 x\n' > "$T/bad3.fnt"
check_fails bad_count "bad3.fnt: line 1: character 65: expected a vertex count" psign -f "$T/bad3.fnt" A
check_fails no_font 'cannot find font file "nosuch.fnt"' psign -f nosuch.fnt A
check_fails bad_option "unknown option: -q" psign -f "$T/sq.fnt" -q A
check_fails no_glyphs "the text has no characters of font" psign -f "$T/sq.fnt" zz

# ---- Radiance's font
if ! radiance_font; then
    skip radiance_font_cases "no Radiance font helvet.fnt (RAYPATH, RADIANCE_LIB or RADIANCE_BIN/../lib)"
    exit 0
fi
same() {   # ID OURS REF
    if [ "$(getinfo -d < "$2" | tr -s ' ')" != "$(getinfo -d < "$3" | tr -s ' ')" ]; then fail "$1" "size $(getinfo -d < "$2")"; return; fi
    r=$(paste <(pvalue -h -H -o "$2") <(pvalue -h -H -o "$3") | awk '{ if ($3 != $8 || $4 != $9 || $5 != $10) bad++ }
        END { printf "%d pixels, %d differ", NR, bad; exit !(NR > 0 && bad == 0) }') && pass "$1" || fail "$1" "$r"
}
while IFS='|' read -r id args; do
    eval psign $args > "$T/$id.hdr" 2> "$T/err" && same "$id" "$T/$id.hdr" "$D/$id.hdr" || fail "$id" "$(head -2 "$T/err")"
done < "$D/cases.txt"
printf 'one\ntwo lines\n  3\n' | psign -h 10 -s -.2 > "$T/stdin.hdr" && same stdin "$T/stdin.hdr" "$D/stdin.hdr"
