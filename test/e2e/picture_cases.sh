#!/bin/bash
# The picture and geometry cases of ../shared/ref/cal (run_pictures.sh,
# run_geom.sh: Radiance 6.1 outputs) that heliodon's pfilt, pextrem, pflip,
# protate, pcompos and getbbox reproduce.  Pictures are compared pixel by
# pixel (decoded floats, relative 1e-6), text exactly.  The commands are
# those of the reference scripts, run from the reference folder.
. test/e2e/lib.sh
C=$REF/cal
if ! have_ref cal/out; then skip picture_cases "no reference folder $REF/cal"; exit 0; fi
T=$(cd "$T" && pwd)
HAVE_FONT=0; radiance_font && HAVE_FONT=1
cd "$C" || exit 1

# floats of a picture (file order), one value a line
pixels() { pvalue -h -H -o -df "$1" | od -An -v -tf4 | tr -s ' ' '\n' | sed '/^$/d'; }
# piccase ID [MAXBAD]: $T/ID.hdr against out/ID.hdr, at most MAXBAD values
# outside 1e-6 relative (default 0)
piccase() {
    pixels "$T/$1.hdr" > "$T/a.txt" 2>/dev/null; pixels "out/$1.hdr" > "$T/b.txt"
    res=$(paste "$T/a.txt" "$T/b.txt" | awk '{d=$1-$2; if(d<0)d=-d; m=$2<0?-$2:$2; if (d > 1e-6*m && d > 1e-30) bad++} END{print NR, bad+0}')
    n=${res% *}; bad=${res#* }
    if [ "$n" -gt 0 ] && [ "$n" -eq "$(wc -l < "$T/b.txt")" ] && [ "$bad" -le "${2:-0}" ]; then pass "$1"
    else fail "$1" "$n values, $bad outside 1e-6"; fi
}
txtcase() { if cmp -s "$T/$1.txt" "out/$1.txt"; then pass "$1"; else fail "$1" "$(diff "$T/$1.txt" "out/$1.txt" | head -3 | tr '\n' ' ')"; fi; }
hdrline() {   # hdrline ID LINE: the output header has this line
    if getinfo < "$T/$1.hdr" | grep -qx "$2"; then pass "$1_header"; else fail "$1_header" "no line '$2'"; fi
}

# ---- pfilt
pfilt -1 -x 64 -y 64 ../scenes/box/a2_clear_fish.hdr > "$T/pf01_fish64.hdr" && piccase pf01_fish64
pfilt -1 -x /4 -y /4 ../scenes/box/a2_clear_persp.hdr > "$T/pf02_persp64.hdr" && piccase pf02_persp64
pfilt -x 64 -y 64 ../scenes/box/a2_clear_persp.hdr > "$T/pf03_twopass.hdr" && piccase pf03_twopass
hdrline pf03_twopass "EXPOSURE=8.4672e-02"
pfilt -1 -e 2 -e +1 -x 64 -y 64 ../scenes/box/a2_clear_persp.hdr > "$T/pf04_exp.hdr" && piccase pf04_exp
hdrline pf04_exp "EXPOSURE=4.0000e+00"
pfilt -1 -r .6 -x 48 -y 48 ../scenes/box/a2_clear_fish.hdr > "$T/pf05_gauss.hdr" && piccase pf05_gauss
pfilt -x 64 -y 64 -h 1000 -n 4 -s .01 ../scenes/box/a2_clear_fish.hdr > "$T/pf06_star.hdr" && piccase pf06_star
# -m: the sun's pixel sums to within one float ulp of an RGBE mantissa
# step, so each contribution must be rounded as Radiance rounds it
pfilt -1 -m .2 -x 32 -y 32 out/pf01_fish64.hdr > "$T/pf07_m.hdr" && piccase pf07_m
check_fails pfilt_bad_option "unknown option" pfilt -q 1 out/pf01_fish64.hdr

# ---- pextrem
(pextrem out/pf01_fish64.hdr; pextrem out/pf04_exp.hdr) > "$T/px01_pextrem.txt" && txtcase px01_pextrem
pextrem -o out/pf04_exp.hdr > "$T/px02_pextrem_o.txt" && txtcase px02_pextrem_o

# ---- pcompos, pflip, protate
pcompos -x 128 -y 64 out/pf01_fish64.hdr 0 0 out/pf02_persp64.hdr 64 0 > "$T/pco01_side.hdr" && piccase pco01_side
pcompos -x 32 -y 32 ../scenes/box/a2_clear_fish.hdr -112 -112 > "$T/pco02_crop.hdr" && piccase pco02_crop
pcompos -b .1 .2 .3 -s 4 -a 2 out/pc07_noinput.hdr out/pc07_noinput.hdr out/pc07_noinput.hdr > "$T/pco03_bg.hdr" && piccase pco03_bg
(pflip -h out/pc07_noinput.hdr | pvalue -h -H -o | sed -n 1,40p; pflip -v out/pc07_noinput.hdr | pvalue -h -H -o | sed -n 1,40p) > "$T/pfl01_flip.txt" && txtcase pfl01_flip
(protate out/pc07_noinput.hdr | pvalue -h -H -o | sed -n 1,40p; protate -r out/pc07_noinput.hdr | pvalue -h -H -o | sed -n 1,40p) > "$T/pro01_rotate.txt" && txtcase pro01_rotate
protate out/pf02_persp64.hdr > "$T/pro02_rotate_pic.hdr" && piccase pro02_rotate_pic
if [ "$(getinfo -d < "$T/pro02_rotate_pic.hdr")" = "$(getinfo -d < out/pro02_rotate_pic.hdr)" ]; then pass pro02_orientation
else fail pro02_orientation "$(getinfo -d < "$T/pro02_rotate_pic.hdr")"; fi

# ---- getbbox
getbbox ../scenes/box/box_room.rad ../scenes/box/box_window.rad > "$T/g01_getbbox.txt" && txtcase g01_getbbox
(getbbox -h -w ../scenes/box/box_room.rad; getbbox -h ../scenes/box/box_window.rad) > "$T/g02_getbbox_w.txt" && txtcase g02_getbbox_w

# ---- pcomb (.cal expressions on pictures)
pcomb -e 'ro=ri(1)*2;go=bi(1);bo=gi(1)*.5' out/pf01_fish64.hdr > "$T/pc01_scale.hdr" && piccase pc01_scale
pcomb -e 'lo=if(li(1)*WE-100,li(1),0)' out/pf01_fish64.hdr > "$T/pc02_lum.hdr" && piccase pc02_lum
pcomb -e 'd(a,b)=if(a-b,a-b,b-a);ro=d(ri(1),ri(2))*nfiles;go=d(gi(1),gi(2));bo=d(bi(1),bi(2))' out/pf01_fish64.hdr out/pf02_persp64.hdr > "$T/pc03_two_inputs.hdr" && piccase pc03_two_inputs
pcomb -s .75 out/pf01_fish64.hdr -s -.25 out/pf02_persp64.hdr > "$T/pc04_s.hdr" && piccase pc04_s
(pcomb -e 'ro=le(1);go=ri(1);bo=pa(1)' out/pf04_exp.hdr | pvalue -h -H -o | sed -n 1,3p; pcomb -e 'ro=le(1);go=ri(1);bo=pa(1)' -o out/pf04_exp.hdr | pvalue -h -H -o | sed -n 1,3p) > "$T/pc05_o.txt" && txtcase pc05_o
pcomb -f inputs/vignette.cal out/pf03_twopass.hdr > "$T/pc06_f.hdr" && piccase pc06_f
pcomb -x 32 -y 32 -e 'b=if(100-(x-16)^2-(y-16)^2,1,0);ro=x/xres+b;go=y/yres;bo=b*.5' > "$T/pc07_noinput.hdr" && piccase pc07_noinput
pcomb -x xmax/2 -y ymax/2 -e 'av(f)=(f(1,0,0)+f(1,1,0)+f(1,0,1)+f(1,1,1))/4;ro=av(ri);go=av(gi);bo=av(bi)' out/pf01_fish64.hdr > "$T/pc08_xy_expr.hdr" && piccase pc08_xy_expr
pcomb -e 'gx=li(1,1,0)-li(1,-1,0);gy=li(1,0,1)-li(1,0,-1);lo=sqrt(gx*gx+gy*gy)' out/pf01_fish64.hdr > "$T/pc09_offsets.hdr" && piccase pc09_offsets
pcomb -c 1 .5 .25 out/pf01_fish64.hdr -s .1 out/pf02_persp64.hdr > "$T/pc10_c.hdr" && piccase pc10_c
if command -v rcollate >/dev/null && command -v total >/dev/null && command -v rcalc >/dev/null; then
    pcomb -h -ff -e 'ro=S(1);go=S(1)*max(-Dy(1),0);bo=li(1)*S(1)*max(-Dy(1),0)' out/pf01_fish64.hdr | rcollate -ho -ff3 -oc 1 | total -if3 > "$T/pc11_view.txt" && txtcase pc11_view
    pcomb -h -ff -e 'ro=Dx(1);go=Dy(1);bo=Dz(1)' out/pf02_persp64.hdr | rcollate -ho -ff3 -oc 1 | rcalc -if3 -e 'r=recno-1;row=floor(r/64);col=r-row*64;m(a)=a-floor(a/16)*16;cond=if(.5-m(row),if(.5-m(col),1,-1),-1);$1=row;$2=col;$3=$1;$4=$2;$5=$3' > "$T/pc12_dirs.txt" && txtcase pc12_dirs
    pcomb -h -ff -e 'ro=ri(1);go=gi(1);bo=bi(1)' out/pf01_fish64.hdr | rcollate -ho -ff3 -oc 1 | total -if3 -m > "$T/pc13_ff.txt" && txtcase pc13_ff
else
    skip pc11_13 "rcollate/total/rcalc not built"
fi
pvalue -h -o "$T/pc07_noinput.hdr" > "$T/pc14_pvalue.txt" && txtcase pc14_pvalue
check_fails pcomb_undefined "undefined" pcomb -e 'ro=nosuch(1)' out/pf01_fish64.hdr
check_fails pcomb_mismatch "resolution mismatch" pcomb out/pf01_fish64.hdr out/pf05_gauss.hdr

# ---- falsecolor: every palette (the tabulated "def" and "tbo" with
# Radiance's interpolation) and mode gives Radiance's pixels within 1e-6
# relative (in fact bit for bit).  With a legend and Radiance's font the
# whole picture, labels included, is compared the same way; without the
# font the labels' text is heliodon's own glyphs, so pixels where either
# picture has grey text (r = g = b) in the legend column are left out and
# the labels are checked by their rows (labelrows below).
falsecolor -i out/pf01_fish64.hdr -s 2000 -n 8 -lw 0 -lh 0 > "$T/fc01_linear.hdr" && piccase fc01_linear
falsecolor -ip out/pf02_persp64.hdr -cl -n 5 -s 1000 -lw 0 -lh 0 > "$T/fc03_cl.hdr" && piccase fc03_cl
falsecolor -i out/pf02_persp64.hdr -cb -m 1 -s 5 -lw 0 -lh 0 > "$T/fc04_cb.hdr" && piccase fc04_cb
falsecolor -i out/pf02_persp64.hdr -cp -pal hot -s 1000 -lw 0 -lh 0 > "$T/fc05_cp.hdr" && piccase fc05_cp
falsecolor -i out/pf02_persp64.hdr -s 500 -r 'v' -g 'v*v' -b '1-v' -lw 0 -lh 0 > "$T/fc07_rgb.hdr" && piccase fc07_rgb
if [ "$(getinfo < "$T/fc05_cp.hdr" | grep -c '^falsecolor -i out/pf02_persp64.hdr -cp -pal hot -s 1000 -lw 0 -lh 0$')" = 1 ]; then pass fc05_header
else fail fc05_header "$(getinfo < "$T/fc05_cp.hdr" | tr '\n' '|')"; fi
pcompos '!falsecolor -i out/pf02_persp64.hdr -pal eco -s 1000 -lw 0 -lh 0' 0 0 '!falsecolor -i out/pf02_persp64.hdr -pal tbo -s 1000 -lw 0 -lh 0' 64 0 '!falsecolor -i out/pf02_persp64.hdr -pal spec -s 1000 -lw 0 -lh 0' 128 0 '!falsecolor -i out/pf02_persp64.hdr -pal pm3d -s 1000 -lw 0 -lh 0' 192 0 > "$T/fc06_pals.hdr" 2>"$T/err" && piccase fc06_pals
# legcase ID OURS REF LEGW: same size; every pixel within 1e-6 relative
# except, outside the 64 x 64 picture (x < LEGW or y >= 64, y from the
# bottom), pixels where either picture is grey (label text, its shadow, or
# a label running past the legend column); at least the picture's 4096
# pixels and some bar pixels compared
legcase() {
    if [ "$(getinfo -d < "$2")" != "$(getinfo -d < "$3")" ]; then fail "$1" "size $(getinfo -d < "$2")"; return; fi
    r=$(paste <(pvalue -h -H -o "$2") <(pvalue -h -H -o "$3") |
        awk -v lw="$4" '{ if (($1 < lw || $2 >= 64) && (($3 == $4 && $4 == $5) || ($8 == $9 && $9 == $10))) next
            n++; if ($1 < lw) nb++
            for (i = 3; i <= 5; i++) { d = $i - $(i + 5); if (d < 0) d = -d; m = $(i + 5); if (m < 0) m = -m; if (d > 1e-6 * m && d > 1e-30) bad++ } }
            END { printf "%d pixels (%d of the bar), %d values outside 1e-6", n, nb, bad; exit !(bad == 0 && n - nb >= 4096 && nb > 500) }') &&
        pass "$1" || fail "$1" "$r"
}
textrows() { pvalue -h -H -o "$1" | awk -v lw="$2" '$1 < lw && $3 >= .5 && $4 >= .5 && $5 >= .5 &&
    ($3 - $4)^2 < .0025 && ($4 - $5)^2 < .0025 { r[$2] = 1 } END { for (y in r) print y }' | sort -n; }
labelrows() {  # ID OURS REF LEGW NLABELS
    textrows "$2" "$4" > "$T/rows.a"; textrows "$3" "$4" > "$T/rows.b"
    na=$(wc -l < "$T/rows.a"); nb=$(wc -l < "$T/rows.b"); miss=$(comm -13 <(sort "$T/rows.a") <(sort "$T/rows.b") | wc -l)
    if [ "$nb" -gt 0 ] && [ "$miss" = 0 ] && [ "$na" -le $((nb + $5)) ]; then pass "$1"
    else fail "$1" "text rows: heliodon $na, Radiance $nb, $miss of Radiance's without text"; fi
}
# With Radiance's font (helvet.fnt through RAYPATH, or RADIANCE_LIB /
# RADIANCE_BIN/../lib) the labels are drawn as Radiance draws them and the
# whole picture is compared; without it heliodon's own glyphs draw them
# and everything but the label text is compared
falsecolor -i out/pf01_fish64.hdr -log 3 -s 100000 -l cd/m2 -d 0 -lw 40 -lh 64 > "$T/fc02_log.hdr"
falsecolor -i out/pf02_persp64.hdr -s a -log 2 -n 4 -lw 30 -lh 64 > "$T/fc08_auto.hdr"
if [ "$HAVE_FONT" = 1 ]; then
    piccase fc02_log
    piccase fc08_auto
else
    legcase fc02_log "$T/fc02_log.hdr" out/fc02_log.hdr 40
    labelrows fc02_label_rows "$T/fc02_log.hdr" out/fc02_log.hdr 40 10
    legcase fc08_auto "$T/fc08_auto.hdr" out/fc08_auto.hdr 30
    labelrows fc08_label_rows "$T/fc08_auto.hdr" out/fc08_auto.hdr 30 6
    skip fc02_fc08_label_text "no Radiance font helvet.fnt (RAYPATH, RADIANCE_LIB or RADIANCE_BIN/../lib): label text not compared"
fi
check_fails falsecolor_bad_palette "invalid palette" falsecolor -i out/pf02_persp64.hdr -pal nosuch
