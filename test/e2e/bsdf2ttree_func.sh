#!/bin/bash
# bsdf2ttree's function form (-t3/-t4 with -e/-f and a .cal function of the
# incident and outgoing directions): analytic Lambertian values, and
# Radiance 6.1's trees of the same functions (bsdf2ttree_func_ref/MANIFEST.md).
. "$(dirname "$0")/lib.sh"
D=$(cd "$(dirname "$0")" && pwd)
X=$D/ttree_expand.awk
R=$D/bsdf2ttree_func_ref
export LC_ALL=C
# blk FILE NAME D G : the block NAME of FILE expanded to its full grid
blk() { awk -v want="$2" '/<WavelengthDataDirection>/ {cur=$0; sub(/.*<WavelengthDataDirection>/, "", cur); sub(/<.*/, "", cur)}
    /<ScatteringData>/ {on=(cur==want); next} /<\/ScatteringData>/ {on=0} on' "$1" | awk -v D=$3 -v G=$4 -f "$X"; }
# const_blk NAME FILE BLOCK D G VALUE : every cell of BLOCK equals VALUE (1e-5 relative);
# rank 3: the first half (incident directions along -x), the rest of the grid stays 0 as in Radiance
const_blk() {
    r=$(blk "$2" "$3" $4 $5 | awk -v v="$6" -v n=$((2 ** ($4 * $5))) -v D=$4 'D == 3 && NR > n/2 {if ($1 != 0) bad++; c++; next}
        {d=$1-v; if (d<0) d=-d; if (d > 1e-5*v) bad++; c++}
        END {print c, bad+0; exit !(c == n && bad == 0)}')
    if [ $? -eq 0 ]; then pass "$1"; else fail "$1" "$3: cells / differing from $6: $r"; fi
}
# same_blk NAME OURS RAD BLOCK D G TOL FRAC : cells within TOL relative except at most FRAC of them
same_blk() {
    r=$(paste <(blk "$2" "$4" $5 $6) <(blk "$3" "$4" $5 $6) | awk -v tol="$7" -v frac="$8" -v n=$((2 ** ($5 * $6))) \
        '{d=$1-$2; if (d<0) d=-d; if (d > tol*($2<0?-$2:$2) + 1e-6) bad++; c++; sa+=$1; sb+=$2}
        END {printf "%d cells, %d differ, totals %.6g / %.6g", c, bad, sa, sb; exit !(c == n && bad <= frac*c)}')
    if [ $? -eq 0 ]; then pass "$1"; else fail "$1" "$4: $r (limit $7 relative, $8 of the cells)"; fi
}
# sum_blk NAME OURS RAD BLOCK D G TOL : block totals within TOL relative
sum_blk() {
    r=$(paste <(blk "$2" "$4" $5 $6) <(blk "$3" "$4" $5 $6) | awk -v tol="$7" -v n=$((2 ** ($5 * $6))) \
        '{sa+=$1; sb+=$2; c++} END {printf "%d cells, totals %.6g / %.6g", c, sa, sb; d=sa-sb; if (d<0) d=-d; exit !(c == n && d <= tol*sb)}')
    if [ $? -eq 0 ]; then pass "$1"; else fail "$1" "$4: $r (limit $7)"; fi
}
nblocks() { grep -c '<WavelengthDataDirection>' "$1"; }

# 1. Lambertian: reflection 0.2, transmission 0.1 -> every cell 0.2/pi or 0.1/pi
L6='lamb(ix,iy,iz,ox,oy,oz) = if(iz*oz, .2/PI, .1/PI)'
L3='lamb3(ix,iy,iz) = if(-iz*Dz, .2/PI, .1/PI)'
check lambert_t3 bash -c "bsdf2ttree -g 4 -t3 +forward -e '$L6' lamb > $T/l3.xml"
check lambert_t4 bash -c "bsdf2ttree -g 3 -t 50 -t4 +forward -e '$L3' lamb3 > $T/l4.xml"
printf 'lampf(ix,iy,iz,ox,oy,oz) = if(iz*oz, rho/PI, tau/PI);\nrho = .2; tau = .1;\n' > "$T/lamb.cal"
TA=$(cd "$T" && pwd)
check lambert_file bash -c "cd $TA && bsdf2ttree -g 3 -t3 -f lamb.cal lampf > $TA/lf.xml"
if [ "$(nblocks "$T/l3.xml")" = 4 ] && [ "$(nblocks "$T/l4.xml")" = 4 ] && [ "$(nblocks "$T/lf.xml")" = 2 ]; then pass blocks
else fail blocks "expected 4, 4, 2 blocks: $(nblocks "$T/l3.xml") $(nblocks "$T/l4.xml") $(nblocks "$T/lf.xml")"; fi
for b in "Reflection Front" "Reflection Back"; do
    const_blk "lambert_t3_${b// /_}" "$T/l3.xml" "$b" 3 4 0.0636620
    const_blk "lambert_t4_${b// /_}" "$T/l4.xml" "$b" 4 3 0.0636620
done
for b in "Transmission Front" "Transmission Back"; do
    const_blk "lambert_t3_${b// /_}" "$T/l3.xml" "$b" 3 4 0.0318310
    const_blk "lambert_t4_${b// /_}" "$T/l4.xml" "$b" 4 3 0.0318310
done
const_blk lambert_file_refl "$T/lf.xml" "Reflection Back" 3 3 0.0636620
# the control: a wrong value is noticed
if blk "$T/l3.xml" "Reflection Back" 3 4 | awk '{d=$1-0.0318310; if (d<0) d=-d; if (d > 1e-5) bad++} END {exit !(bad > 0)}'; then
    pass lambert_control; else fail lambert_control "the reflection block equals the transmission value"; fi

# 2. Radiance's trees of the same functions: without super-sampling (-s 1000)
# every cell is the function at the cell centres -> equal to 1e-3 (Radiance
# prints 4 digits; a rare reduction decision may differ: 0.5 % of the cells)
PH='phong(ix,iy,iz,ox,oy,oz) = if(iz, .1+((iz+oz)/sqrt((ix+ox)^2+(iy+oy)^2+(iz+oz)^2))^50, 0)'
AN='an(ix,iy,iz) = if(-iz*Dz, .05 + 2*exp(-((ix-Dx)^2*40 + (iy-Dy)^2*4)), .02)'
gzip -dc "$R/phong_g5_s1000.xml.gz" > "$T/rad_phong.xml"
gzip -dc "$R/an_g4_s1000.xml.gz" > "$T/rad_an_s.xml"
gzip -dc "$R/an_g4.xml.gz" > "$T/rad_an.xml"
check phong_t3 bash -c "bsdf2ttree -g 5 -s 1000 -t3 -e '$PH' phong > $T/phong.xml"
for b in "Reflection Back" "Transmission Back"; do
    same_blk "phong_${b// /_}" "$T/phong.xml" "$T/rad_phong.xml" "$b" 3 5 1e-3 0.005
done
check an_t4 bash -c "bsdf2ttree -g 4 -s 1000 -N 2 -t4 +forward -e '$AN' an > $T/an_s.xml"
for b in "Reflection Front" "Transmission Front" "Reflection Back" "Transmission Back"; do
    same_blk "an_${b// /_}" "$T/an_s.xml" "$T/rad_an_s.xml" "$b" 4 4 1e-3 0.005
done
# with super-sampling (random in both programs): block totals within 0.5 %
check an_t4_ss bash -c "bsdf2ttree -g 4 -t4 +forward -e '$AN' an > $T/an.xml"
for b in "Reflection Front" "Reflection Back"; do
    sum_blk "an_ss_${b// /_}" "$T/an.xml" "$T/rad_an.xml" "$b" 4 4 0.005
done
# same output whatever the thread count
bsdf2ttree -g 4 -t4 -N 1 -e "$AN" an > "$T/an1.xml" 2>/dev/null
bsdf2ttree -g 4 -t4 -N 2 -e "$AN" an > "$T/an2.xml" 2>/dev/null
if cmp -s <(grep -v 'Created by' "$T/an1.xml") <(grep -v 'Created by' "$T/an2.xml"); then pass threads_same; else fail threads_same "-N 1 and -N 2 trees differ"; fi

# 3. errors
check_fails fn_undefined "nosuch: not defined" bsdf2ttree -t3 -e "$PH" nosuch
check_fails fn_nargs "f2: wrong number of arguments" bsdf2ttree -t4 -e 'f2(a,b) = a+b' f2
check_fails fn_variable "v: a variable" bsdf2ttree -t4 -e 'v = 1' v
check_fails fn_missing "no BSDF function named" bsdf2ttree -t3 -e "$PH"
check_fails fn_syntax "unexpected character" bsdf2ttree -t3 -e 'f(a,b,c) = (a+' f
check_fails fn_nofile "cannot find file 'nosuch.cal'" bsdf2ttree -t3 -f nosuch.cal f
check_fails fn_not_last "must be the last argument" bsdf2ttree -t3 -e "$PH" phong extra
check_fails fn_runtime "undefined" bsdf2ttree -g 2 -t3 -e 'f(a,b,c) = a + nosuchvar' f
