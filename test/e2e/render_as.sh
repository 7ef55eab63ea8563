#!/bin/bash
# rtrace -as: Radiance's ambient super-sampling (walk.c).  A closed grey
# box whose only light is a small opening onto a bright glow: the few
# hemisphere divisions that see the opening are far brighter than their
# neighbours, get most of the extra samples, and are averaged down, so
# Radiance's -as estimate is biased low (to a third at the first point).
# heliodon must give Radiance 6.1's mean at -as 0 and at -as 512 (reference
# in test/data/render_as, commands in its MANIFEST.md) within 3.5 combined
# standard errors per point (400 rays per point in each program).
. test/e2e/lib.sh
D=test/data/render_as
for as in 0 512; do
    awk '{for (k = 0; k < 400; k++) print}' "$D/points.txt" |
        rtrace -h -I -ab 1 -ad 256 -as $as "$D/box.rad" > "$T/as$as.out" 2>"$T/as$as.err"
    awk '{p = int((NR - 1) / 400); s[p] += $1; q[p] += $1 * $1}
         END {for (p = 0; p < 4; p++) {m = s[p] / 400; printf "%.6f %.6f\n", m, sqrt((q[p] / 400 - m * m) / 400)}}' \
        "$T/as$as.out" > "$T/as$as.txt"
    if [ "$(wc -l < "$T/as$as.txt")" = 4 ] && paste "$T/as$as.txt" "$D/radiance_as$as.txt" |
        awk '{d = $1 - $3; if (d < 0) d = -d; if (!(d <= 3.5 * sqrt($2 * $2 + $4 * $4))) bad++} END {exit bad > 0}'; then
        pass "as${as}_radiance"
    else
        fail "as${as}_radiance" "heliodon / Radiance (mean se): $(paste "$T/as$as.txt" "$D/radiance_as$as.txt" | tr '\n\t' '; ') $(head -c 200 "$T/as$as.err")"
    fi
done
# the bias itself: super-sampling takes the first point below half its -as 0 value
if paste "$T/as0.txt" "$T/as512.txt" | awk 'NR == 1 {exit !($3 < 0.5 * $1)}'; then
    pass as_bias
else
    fail as_bias "first point: -as 0 / -as 512: $(paste "$T/as0.txt" "$T/as512.txt" | head -1)"
fi
# the defaults are Radiance's: rtrace 512, rpict 128 (the same bytes as given explicitly;
# Radiance 6.1 rpict -x 32 -y 32 -ps 1 -ab 1 -ad 64 -aa 0 of this view: mean 0.0429 at -as 0,
# 0.0084 at -as 128; heliodon 0.0406 and 0.0108)
awk 'NR == 1 {for (k = 0; k < 50; k++) print}' "$D/points.txt" > "$T/p50"
rtrace -h -I -ab 1 -ad 256 "$D/box.rad" < "$T/p50" > "$T/d.out" 2>&1
rtrace -h -I -ab 1 -ad 256 -as 512 "$D/box.rad" < "$T/p50" > "$T/d512.out" 2>&1
rtrace -h -I -ab 1 -ad 256 -as 128 "$D/box.rad" < "$T/p50" > "$T/d128.out" 2>&1
check as_default_rtrace bash -c "cmp '$T/d.out' '$T/d512.out' && ! cmp -s '$T/d.out' '$T/d128.out'"
V="-vp 3 2 1.5 -vd -1 0 -0.3 -vu 0 0 1 -vh 60 -vv 60"
rpict -x 16 -y 16 -ab 1 -ad 64 $V "$D/box.rad" 2>/dev/null | pvalue -h -H -d > "$T/r.txt"
rpict -x 16 -y 16 -ab 1 -ad 64 -as 128 $V "$D/box.rad" 2>/dev/null | pvalue -h -H -d > "$T/r128.txt"
rpict -x 16 -y 16 -ab 1 -ad 64 -as 0 $V "$D/box.rad" 2>/dev/null | pvalue -h -H -d > "$T/r0.txt"
check as_default_rpict bash -c "test -s '$T/r.txt' && cmp '$T/r.txt' '$T/r128.txt' && ! cmp -s '$T/r.txt' '$T/r0.txt'"
