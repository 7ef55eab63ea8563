# falsecolor -palettes, -e and -odim/-orct against Radiance 6.1's outputs
# (test/data/falsecolor, commands in MANIFEST.md there).
#  -palettes: the 256 x 300 chart; its six colour bars (one row of each,
#    taken with pcomb as in the MANIFEST) within 1e-6 relative, the names
#    drawn in the label rows at the left and nothing else there.
#  -e: with Radiance's font (helvet.fnt through RAYPATH, or RADIANCE_LIB /
#    RADIANCE_BIN/../lib) the whole picture, labels included, within 1e-6
#    relative of Radiance's.  Without it the labels are heliodon's glyphs:
#    the picture outside the two labels within 1e-6 relative; each label a
#    box on the same rows as Radiance's (32 high, centred on the extreme
#    pixel) covering that pixel (box widths differ by a few pixels, and a
#    box reaching past the right edge widens the picture, as in Radiance,
#    by that much).
. test/e2e/lib.sh
T=$(cd "$T" && pwd)
HAVE_FONT=0; radiance_font && HAVE_FONT=1
D=$(pwd)/test/data/falsecolor
C=$REF/cal
# pixels A B: "x y r g b" of A and B side by side (pvalue, original values)
pixels() { paste <(pvalue -h -H -o "$1") <(pvalue -h -H -o "$2"); }
relcmp() { awk '{ for (i = 3; i <= 5; i++) { d = $i - $(i + 5); if (d < 0) d = -d; m = $(i + 5); if (m < 0) m = -m; if (d > 1e-6 * m && d > 1e-30) bad++ } }
    END { printf "%d pixels, %d values outside 1e-6", NR, bad; exit !(NR > 0 && bad == 0) }'; }

# ---- -palettes
falsecolor -palettes > "$T/pal.hdr" 2> "$T/err" || fail palettes_run "$(head -2 "$T/err")"
[ "$(getinfo -d < "$T/pal.hdr" | tr -s ' ')" = "-Y 300 +X 256" ] && pass palettes_size || fail palettes_size "$(getinfo -d < "$T/pal.hdr")"
pcomb -x 256 -y 6 -e 'ro=ri(1);go=gi(1);bo=bi(1)' - < "$T/pal.hdr" > "$T/bars.hdr"
r=$(pixels "$T/bars.hdr" "$D/palettes_bars.hdr" | relcmp) && pass palettes_bars || fail palettes_bars "$r"
# label rows (y mod 50 >= 30, y from the bottom): text (r = g = b > 0) at
# x < 60 in each of the six, black from x = 64 on
r=$(pvalue -h -H -o "$T/pal.hdr" | awk '$2 % 50 >= 30 { k = int($2 / 50)
        if ($1 >= 64 && ($3 > 0 || $4 > 0 || $5 > 0)) stray++
        if ($1 < 60 && $3 > .5 && $3 == $4 && $4 == $5) ink[k]++ }
    END { for (k = 0; k < 6; k++) if (ink[k] < 20) miss++; printf "%d stray pixels, %d names missing", stray, miss; exit !(stray == 0 && miss == 0) }') &&
    pass palettes_names || fail palettes_names "$r"
# with the font: the names' rows of the left 64 columns as Radiance's
if [ "$HAVE_FONT" = 1 ]; then
    pcompos -x 64 -y 300 "$T/pal.hdr" 0 0 | pcomb -e 'lab=if(y-floor(y/50)*50-29.5,1,0);ro=lab*ri(1);go=lab*gi(1);bo=lab*bi(1)' - > "$T/names.hdr"
    r=$(pixels "$T/names.hdr" "$D/palettes_names.hdr" | relcmp) && pass palettes_names_font || fail palettes_names_font "$r"
else
    skip palettes_names_font "no Radiance font helvet.fnt: names drawn with heliodon's glyphs"
fi

# ---- -e
if ! have_ref cal/out; then skip extrema "no reference folder $REF/cal"; exit 0; fi
# excase ID REF LEGW XMIN YMIN XMAX YMAX: heliodon's output ($T/ID.hdr)
# and the same without -e ($T/ID.noe.hdr) against Radiance's REF; XMIN.. =
# the extreme pixels in the output (x includes the legend's width LEGW);
# label rows compared right of the legend (its own labels' text differs)
excase() {
    id=$1 ref=$2 lw=$3 x0=$4 y0=$5 x1=$6 y1=$7
    w=$(getinfo -d < "$T/$id.hdr" | awk '{ print $4 }'); wr=$(getinfo -d < "$ref" | awk '{ print $4 }')
    hh=$(getinfo -d < "$T/$id.hdr" | awk '{ print $2 }'); hr=$(getinfo -d < "$ref" | awk '{ print $2 }')
    if [ "$hh" = "$hr" ] && [ "$w" -ge "$wr" ] && [ "$w" -le $((wr + 4)) ]; then pass "${id}_size"; else fail "${id}_size" "$w x $hh vs $wr x $hr"; fi
    # pcompos onto Radiance's size, so the pixels pair up
    pcompos -x "$wr" -y "$hr" "$T/$id.hdr" 0 0 > "$T/$id.c.hdr"
    pcompos -x "$wr" -y "$hr" "$T/$id.noe.hdr" 0 0 > "$T/$id.n.hdr"
    # columns: ours, Radiance's, without -e -> x y changed-ours changed-radiance equal
    paste <(pvalue -h -H -o "$T/$id.c.hdr") <(pvalue -h -H -o "$ref") <(pvalue -h -H -o "$T/$id.n.hdr") |
        awk '{ co = ($3 != $13 || $4 != $14 || $5 != $15); cr = ($8 != $13 || $9 != $14 || $10 != $15)
               print $1, $2, co, cr, ($3 == $8 && $4 == $9 && $5 == $10) }' > "$T/$id.m"
    r=$(awk '!$3 && !$4 { n++; if (!$5) bad++ } END { printf "%d pixels outside the labels, %d differ", n, bad; exit !(n > 400 && bad == 0) }' "$T/$id.m") &&
        pass "${id}_picture" || fail "${id}_picture" "$r"
    r=$(awk -v lw="$lw" -v x0="$x0" -v y0="$y0" -v x1="$x1" -v y1="$y1" '
        $1 >= lw && $3 { ro[$2] = 1 } $1 >= lw && $4 { rr[$2] = 1 }
        ($1 == x0 && $2 == y0) || ($1 == x1 && $2 == y1) { if ($3) co++; if ($4) cr++ }
        END { for (y in rr) if (!(y in ro)) miss++; for (y in ro) if (!(y in rr)) extra++
              printf "rows: %d of Radiance'"'"'s not ours, %d ours not Radiance'"'"'s; extreme pixels covered %d/%d", miss, extra, co, cr
              exit !(miss == 0 && extra == 0 && co == 2 && cr == 2) }' "$T/$id.m") &&
        pass "${id}_labels" || fail "${id}_labels" "$r"
}
# fullcase ID REF: the same size as REF and every pixel within 1e-6
fullcase() {
    if [ "$(getinfo -d < "$T/$1.hdr")" != "$(getinfo -d < "$2")" ]; then fail "$1_font" "size $(getinfo -d < "$T/$1.hdr")"; return; fi
    r=$(pixels "$T/$1.hdr" "$2" | relcmp) && pass "$1_font" || fail "$1_font" "$r"
}
cd "$C" || exit 1

# ---- -odim/-orct value overlays: the pixels the overlay changes (the
# output against the same without it, pcompos'd to its size: changed
# pixels kept, others black) against Radiance's (MANIFEST.md); errors
# exit 255 with Radiance's messages
P=../scenes/box/a2_clear_persp.hdr
M='ne(a,b)=if(a-b,1,if(b-a,1,0));m=max(ne(ri(1),ri(2)),max(ne(gi(1),gi(2)),ne(bi(1),bi(2))));ro=m*ri(1);go=m*gi(1);bo=m*bi(1)'
falsecolor -i $P -s 1000 -odim 4 4 -lw 0 -lh 0 > "$T/oA.hdr"
falsecolor -i $P -s 1000 -lw 0 -lh 0 | pcompos -x 256 -y 257 - 0 0 > "$T/oA0.hdr"
pcomb -e "$M" "$T/oA.hdr" "$T/oA0.hdr" > "$T/overlay_4x4.hdr"
falsecolor -i $P -s 1000 -odim 3 2 -orct 20 30 236 230 -e > "$T/oB.hdr"
falsecolor -i $P -s 1000 > "$T/oB0.hdr"
pcomb -e "$M" "$T/oB.hdr" "$T/oB0.hdr" > "$T/overlay_rect_e.hdr"
# the overlay's text sits 1 row above the picture: one more row (257)
[ "$(getinfo -d < "$T/oA.hdr" | tr -s ' ')" = "-Y 257 +X 256" ] && pass overlay_size || fail overlay_size "$(getinfo -d < "$T/oA.hdr")"
for id in overlay_4x4 overlay_rect_e; do
    if [ "$HAVE_FONT" = 1 ]; then
        r=$(pixels "$T/$id.hdr" "$D/$id.hdr" | relcmp) && pass "$id" || fail "$id" "$r"
    else    # heliodon's glyphs: labels on Radiance's rows
        r=$(pixels "$T/$id.hdr" "$D/$id.hdr" | awk '$3 > 0 { o[$2] = 1 } $8 > 0 { r[$2] = 1 }
            END { for (y in r) if (!(y in o)) miss++; printf "%d of Radiance'"'"'s label rows without labels", miss; exit miss > 2 }') &&
            pass "${id}_rows" || fail "${id}_rows" "$r"
    fi
done
[ "$HAVE_FONT" = 1 ] || skip overlay_text "no Radiance font helvet.fnt: overlay values drawn with heliodon's glyphs"
falsecolor -i $P -odim 8 8 -lw 0 -lh 0 > /dev/null 2> "$T/err"; rc=$?
[ $rc = 255 ] && grep -q "Overlay matrix spacing too tight" "$T/err" && pass overlay_too_tight || fail overlay_too_tight "exit $rc: $(cat "$T/err")"
falsecolor -i $P -odim 2 2 -orct 10 10 5 5 > /dev/null 2> "$T/err"; rc=$?
[ $rc = 255 ] && grep -q "Illegal overlay rectangle" "$T/err" && pass overlay_bad_rect || fail overlay_bad_rect "exit $rc: $(cat "$T/err")"

if [ "$HAVE_FONT" = 1 ]; then
    falsecolor -i out/pf02_persp64.hdr -e -s 1000 -lw 0 -lh 0 > "$T/nolegend.hdr" && fullcase nolegend "$D/extrema_nolegend.hdr"
    falsecolor -i out/pf01_fish64.hdr -e -log 3 -s 100000 -lw 40 -lh 64 -d 1 > "$T/legend.hdr" && fullcase legend "$D/extrema_legend.hdr"
    falsecolor -c0 -e < out/pf02_persp64.hdr > "$T/c0.hdr" && fullcase c0 "$D/extrema_c0_stdin.hdr"
    exit 0
fi
skip extrema_font "no Radiance font helvet.fnt: labels drawn with heliodon's glyphs, their text not compared"
falsecolor -i out/pf02_persp64.hdr -e -s 1000 -lw 0 -lh 0 > "$T/nolegend.hdr" &&
    falsecolor -i out/pf02_persp64.hdr -s 1000 -lw 0 -lh 0 > "$T/nolegend.noe.hdr" &&
    excase nolegend "$D/extrema_nolegend.hdr" 0 7 20 11 47
falsecolor -i out/pf01_fish64.hdr -e -log 3 -s 100000 -lw 40 -lh 64 -d 1 > "$T/legend.hdr" &&
    falsecolor -i out/pf01_fish64.hdr -log 3 -s 100000 -lw 40 -lh 64 -d 1 > "$T/legend.noe.hdr" &&
    excase legend "$D/extrema_legend.hdr" 40 63 24 67 36
falsecolor -c0 -e < out/pf02_persp64.hdr > "$T/c0.hdr" &&
    falsecolor -c0 < out/pf02_persp64.hdr > "$T/c0.noe.hdr" &&
    excase c0 "$D/extrema_c0_stdin.hdr" 0 7 20 11 47
