#!/bin/bash
# pmcompose -G (sunlit fraction of the exterior ground per sun patch) on synthetic coefficients:
# 4x4 pictures, sky DC = 1 for the ground bin (0) and 0 for the 145 sky patches, DC_sun = 0, so
# the composite's luminance is 179 x the ground bin of the hour's sky vector.  With fraction f the
# ground bin is rho (E_diff + f E_dir sin alt) / pi: f = 1 equals no -G, f = 0.5 is the mean of
# f = 0 and f = 1, and L(1) - L(0) = 179 x rho x E_dir sin(alt) / pi with E_dir = the sun patch's
# disk radiance (hours log) x the 0.533-degree disk's solid angle and alt from gendaylit (1 %).
. test/e2e/lib.sh
mkdir -p "$T/k" "$T/s"
pic() { awk -v v="$1" 'BEGIN{for (i = 0; i < 16; i++) print v, v, v}' | pvalue -r -h -H -da -y 4 +x 4; }
pic 1 > "$T/one.hdr" && pic 0 > "$T/zero.hdr" || { fail pictures "pvalue -r"; exit 0; }
cp "$T/one.hdr" "$T/k/000.hdr"
for b in $(seq 1 145); do cp "$T/zero.hdr" "$T/k/$(printf %03d "$b").hdr"; cp "$T/zero.hdr" "$T/s/solar$b.hdr"; done
izmir_wea "$T/w.wea" '3 21 10.5 820 110'
echo "rview -vta -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180" > "$T/v.vf"
run() {  # name [fraction]: mean luminance of the hour
    if [ -n "${2:-}" ]; then printf '%s %s\n' "$bin" "$2" > "$T/$1.txt"; set -- "$1" -G "$T/$1.txt"; fi
    pmcompose -w "$T/w.wea" -vf "$T/v.vf" -s "$T/s/solar%d.hdr" -k "$T/k/%03d.hdr" "${@:2}" -o /dev/null -L "$T/$1.log" \
        2>> "$T/err.txt" && grep -v '^#' "$T/$1.log" | awk '{print $12}'
}
bin=0
lnone=$(run none) && bin=$(grep -v '^#' "$T/none.log" | awk '{print $5}')
if [ "$bin" -gt 0 ] 2>/dev/null; then pass sun_patch; else fail sun_patch "no sun patch in $T/none.log: $(tail -2 "$T/err.txt")"; exit 0; fi
l1=$(run g1 1); l0=$(run g0 0); l5=$(run g5 0.5)
if [ "$l1" = "$lnone" ]; then pass fraction_one_is_default; else fail fraction_one_is_default "$l1 vs $lnone"; fi
if close "$l5" "$(awk -v a="$l0" -v b="$l1" 'BEGIN{print (a + b) / 2}')" 0.001; then pass fraction_linear
else fail fraction_linear "L(0.5) $l5, L(0) $l0, L(1) $l1"; fi
read -r sr dz < <(grep -v '^#' "$T/none.log" | awk '{print $9, $8}')
alt=$(gendaylit 3 21 10.5 -a 38.4 -o -27.1 -m -30 -W 820 110 | awk '/altitude/ {print $(NF - 1)}')
want=$(awk -v L="$sr" -v a="$alt" 'BEGIN{pi = 3.14159265358979; om = 2 * pi * (1 - cos(0.2665 * pi / 180));
    print 179 * 1.0039 * 0.2 * L * om * sin(a * pi / 180) / pi}')
got=$(awk -v a="$l1" -v b="$l0" 'BEGIN{print a - b}')
echo "ground sun term: L(1) - L(0) = $got cd/m2, expected $want (sun radiance $sr, altitude $alt)" >&2
if close "$got" "$want" 0.01; then pass ground_sun_term; else fail ground_sun_term "L(1) - L(0) = $got, expected $want"; fi
if awk -v a="$l0" 'BEGIN{exit !(a > 0)}'; then pass diffuse_part_kept; else fail diffuse_part_kept "L(0) = $l0"; fi
# sensor mode (-E): the 16 pixels are 16 points; each point's lux = 179 x the luminance weights of
# its composed value = here the hour's mean luminance of the glare run (every pixel equal)
if pmcompose -w "$T/w.wea" -s "$T/s/solar%d.hdr" -k "$T/k/%03d.hdr" -E "$T/e.csv" -L "$T/e.log" 2>> "$T/err.txt" &&
   [ "$(head -1 "$T/e.csv" | tr ',' '\n' | wc -l)" = 20 ] && [ "$(head -1 "$T/e.csv" | cut -d, -f1-5)" = "record,month,day,hour,E1" ] &&
   [ "$(wc -l < "$T/e.csv")" = 2 ] &&
   tail -1 "$T/e.csv" | awk -F, -v L="$lnone" '{for (i = 5; i <= NF; i++) {d = $i - L; if (d < 0) d = -d; if (d > 1e-4 * L) exit 1}}'; then
    pass sensor_mode
else fail sensor_mode "$(head -2 "$T/e.csv" 2>/dev/null | tr '\n' ' ') vs $lnone; $(tail -1 "$T/err.txt")"; fi
# -noglare: any view (a perspective one here), hour log only, the same composition
echo "rview -vtv -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 60 -vv 60" > "$T/p.vf"
if pmcompose -w "$T/w.wea" -vf "$T/p.vf" -s "$T/s/solar%d.hdr" -k "$T/k/%03d.hdr" -noglare -L "$T/ng.log" -o "$T/ng.csv" 2>> "$T/err.txt" &&
   [ "$(grep -v '^#' "$T/ng.log" | awk '{print $12}')" = "$lnone" ] && [ ! -e "$T/ng.csv" ]; then pass noglare_mode
else fail noglare_mode "$(tail -1 "$T/err.txt")"; fi
check_fails glare_needs_fisheye "fisheye|-vta|-vth" pmcompose -w "$T/w.wea" -vf "$T/p.vf" -s "$T/s/solar%d.hdr" -k "$T/k/%03d.hdr" -o /dev/null
