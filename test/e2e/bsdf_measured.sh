#!/bin/bash
# Measured BSDFs: synthetic PAB-Opto files (made at test time by the
# reference folder's generator) -> pabopto2bsdf -> bsdf2ttree, compared with
# Radiance 6.1's trees of the same data (ref/bsdf/measured, MANIFEST.md),
# with the analytic model the files were sampled from, and bad input files.
. "$(dirname "$0")/lib.sh"
if ! have_ref bsdf/measured; then skip all "no reference folder $REF/bsdf/measured"; exit 0; fi
M=$(cd "$REF/bsdf/measured" && pwd)   # absolute: the generator runs in $T
if ! command -v python3 >/dev/null 2>&1; then skip all "python3 (for synth_pabopto.py) not found"; exit 0; fi
export LC_ALL=C
# 1. the measurement files (13 MB, not kept), checked against the reference md5 list
cp "$M/synth_pabopto.py" "$T/"
if ! (cd "$T" && python3 synth_pabopto.py >/dev/null 2>&1 && grep -E 'fabric_|film_tb|film_rf' "$M/meas.md5" | md5sum -c --quiet -); then
    fail synth "the generated measurement files differ from meas.md5"; exit 0
fi
pass synth

# checkBSDF report -> "component lambertian maxdir" lines
cb() { awk -F'\t' '/Refl|Trans/ && split($2, l, " ") == 3 {m=$4; gsub(/[ %]/, "", m); gsub(/ /, "_", $1); print $1, l[1], m}' "$1"; }
# cbcmp NAME A B TOL : every figure of report A within TOL percentage points of report B
cbcmp() {
    cb "$2" > "$T/cb.a"; cb "$3" > "$T/cb.b"
    r=$(awk -v tol="$4" 'NR==FNR {a[$1" "$2]=$3" "$4; n++; next}
        {k=$1" "$2; split(a[k], v, " "); for (i=1;i<=2;i++) {d=v[i]-$(i+2); if (d<0) d=-d; if (d>mx) mx=d}; m++}
        END {if (n != m || n < 4) {print "rows " n " vs " m; exit 1} printf "%.2f", mx; exit !(mx <= tol)}' "$T/cb.a" "$T/cb.b")
    if [ $? -eq 0 ]; then pass "$1"; else fail "$1" "largest difference $r pp (limit $4)"; fi
}
# klems_cmp NAME A B LIM : T matrices (rmtxop -fa): mean element-wise relative difference
# (sum|a-b|/sum|b|) <= 5 %, directional-hemispherical per incident patch within LIM
# (grazing ring, the last 12 patches, excluded)
klems_cmp() {
    r=$(awk -v lim="$4" 'function lam(k,  r,c,lo,hi) { c=0; for (r=1;r<=9;r++) { if (k < c+np[r]) break; c+=np[r] }
                lo=tb[r]*3.14159265/180; hi=tb[r+1]*3.14159265/180; return 3.14159265*(sin(hi)^2-sin(lo)^2)/np[r] }
        BEGIN { split("1 8 16 20 24 24 24 16 12", np, " "); split("0 5 15 25 35 45 55 65 75 90", tb, " ") }
        FNR==1 {f++; row=0; hdr=1} hdr && /^$/ {hdr=0; next} hdr {next}
        { for (j=0;j<145;j++) { v=$(3*j+1); if (f==1) a[row,j]=v; else b[row,j]=v }; row++ }
        END { for (i=0;i<145;i++) for (j=0;j<145;j++) { d=a[i,j]-b[i,j]; sd+=(d<0?-d:d); sb+=b[i,j]; ha[j]+=a[i,j]*lam(i); hb[j]+=b[i,j]*lam(i) }
              for (j=0;j<133;j++) { d=(ha[j]-hb[j])/hb[j]; if (d<0) d=-d; if (d>mx) mx=d }
              printf "%.4f %.4f", sd/sb, mx; exit !(sd/sb <= .05 && mx <= lim) }' "$2" "$3")
    if [ $? -eq 0 ]; then pass "$1"; else fail "$1" "mean element-wise / largest per-patch difference $r (limits 0.05 / $4)"; fi
}

# 2. interpolants and the -g 5 -t 90 tree, as in the reference
ok=1
for c in tb rb tf rf; do
    pabopto2bsdf "$T"/meas/fabric_$c/*.txt > "$T/fabric_$c.sir" 2> "$T/p2b.err" || { ok=0; fail pabopto2bsdf_$c "$(head -2 "$T/p2b.err")"; }
done
[ $ok = 1 ] && pass pabopto2bsdf
check bsdf2ttree bash -c "bsdf2ttree -g 5 -t 90 $T/fabric_tb.sir $T/fabric_rb.sir $T/fabric_tf.sir $T/fabric_rf.sir > $T/ours.xml"
check bsdf2ttree_radsir bash -c "bsdf2ttree -g 5 -t 90 $M/fabric_tb.sir $M/fabric_rb.sir $M/fabric_tf.sir $M/fabric_rf.sir > $T/radsir.xml"
# the thread count changes nothing: interpolant (after its header) and tree
pabopto2bsdf -n 1 "$T"/meas/fabric_tb/*.txt > "$T/n1.sir" 2>/dev/null
if cmp -s <(sed -n '/^$/,$p' "$T/n1.sir") <(sed -n '/^$/,$p' "$T/fabric_tb.sir"); then pass pabopto2bsdf_threads
else fail pabopto2bsdf_threads "-n 1 and the default thread count give different interpolants"; fi
bsdf2ttree -N 1 -g 5 -t 90 $T/fabric_tb.sir $T/fabric_rb.sir $T/fabric_tf.sir $T/fabric_rf.sir > "$T/n1.xml"
bsdf2ttree -N 2 -g 5 -t 90 $T/fabric_tb.sir $T/fabric_rb.sir $T/fabric_tf.sir $T/fabric_rf.sir > "$T/n2.xml"
if cmp -s <(sed 1,2d "$T/n1.xml") <(sed 1,2d "$T/n2.xml"); then pass bsdf2ttree_threads; else fail bsdf2ttree_threads "-N 1 and -N 2 trees differ"; fi
checkBSDF "$T/ours.xml" > "$T/ours.cb" 2>/dev/null
checkBSDF "$T/radsir.xml" > "$T/radsir.cb" 2>/dev/null
checkBSDF "$M/fabric_g5_t90.xml" > "$T/rad.cb" 2>/dev/null
cbcmp checkbsdf_ours_vs_radiance "$T/ours.cb" "$M/fabric_g5_t90.checkBSDF.txt" 1.0
cbcmp checkbsdf_radsir_vs_radiance "$T/radsir.cb" "$M/fabric_g5_t90.checkBSDF.txt" 1.0
cbcmp checkbsdf_same_tool "$T/ours.cb" "$T/rad.cb" 1.0

# 3. Klems T matrices (bsdf2klems with the reference's 1024 samples per patch pair), the
# issue's limits (5 % mean element-wise, 2 % per incident patch, grazing ring excluded) for
# Radiance's interpolants through our bsdf2ttree and for our whole pipeline (pabopto2bsdf makes
# Radiance's transport plans: test_rbf_plan; the least-cost plans of -x move the 0-15 degree
# patches by up to 2.4 %, docs/design/measured.md)
gzip -dc "$M/fabric_g5_t90_klems_T.mtx.gz" > "$T/rad_T.mtx"
bsdf2klems -n 1024 "$T/radsir.xml" > "$T/radsir_klems.xml" && rmtxop -fa "$T/radsir_klems.xml" > "$T/radsir_T.mtx"
klems_cmp klems_T_radsir "$T/radsir_T.mtx" "$T/rad_T.mtx" 0.02
bsdf2klems -n 1024 "$T/ours.xml" > "$T/ours_klems.xml" && rmtxop -fa "$T/ours_klems.xml" > "$T/ours_T.mtx"
klems_cmp klems_T_ours "$T/ours_T.mtx" "$T/rad_T.mtx" 0.02

# 4. directional-hemispherical transmission of the analytic model, ring by
# ring (0.10 Lambertian + 0.014 A(tan theta) direct): our error is at most
# Radiance's own (its tree's Klems matrix in the reference) + 0.1 percentage point
r=$(awk 'function lam(k,  r,c,lo,hi) { c=0; for (r=1;r<=9;r++) { if (k < c+np[r]) break; c+=np[r] }
            lo=tb[r]*pi/180; hi=tb[r+1]*pi/180; return pi*(sin(hi)^2-sin(lo)^2)/np[r] }
    function ring(k,  r,c) { c=0; for (r=1;r<=9;r++) { if (k < c+np[r]) return r; c+=np[r] } }
    function A(x) { return x >= 1 ? 0 : (2/pi)*(atan2(sqrt(1-x*x), x) - x*sqrt(1-x*x)) }
    BEGIN { pi=3.14159265358979; split("1 8 16 20 24 24 24 16 12", np, " "); split("0 5 15 25 35 45 55 65 75 90", tb, " ")
            split("0 10 20 30 40 50 60 70 82.5", tc, " ") }
    FNR==1 {f++; row=0; hdr=1} hdr && /^$/ {hdr=0; next} hdr {next}
    { for (j=0;j<145;j++) h[f,j]+=$(3*j+1)*lam(row); row++ }
    END { for (j=0;j<133;j++) { q=ring(j); s[1,q]+=h[1,j]/lam(j); s[2,q]+=h[2,j]/lam(j); n[q]++ }
          for (q=1;q<=8;q++) { m=0.10+0.014*A(sin(tc[q]*pi/180)/cos(tc[q]*pi/180))
              eo=s[1,q]/n[q]-m; er=s[2,q]/n[q]-m; eo=eo<0?-eo:eo; er=er<0?-er:er
              if (eo > er+0.001) bad=bad sprintf(" ring%d: %.4f vs %.4f", q, eo, er); if (eo>mo) mo=eo; if (er>mr) mr=er }
          printf "%.4f %.4f%s", mo, mr, bad; exit bad != "" }' "$T/ours_T.mtx" "$T/rad_T.mtx")
if [ $? -eq 0 ]; then pass model_hemispherical; else fail model_hemispherical "ours / Radiance largest error: $r"; fi

# 4b. the anisotropic film (light from the exterior, 41 incident directions, 113 mesh edges):
# our whole pipeline against Radiance's film_tb_g5_t90 at the issue's limits: checkBSDF within
# 1 point, Klems T within 5 % mean element-wise and 2 % per incident patch (grazing ring
# excluded); measured 0.1 point, 0.60 % mean, 0.64 % worst patch (0.71 % with the grazing ring).
# The mesh's triangles overlap near 50-65 degrees, so which one holds a direction depends on the
# order of the walk over the mesh, hence on the edge order of the file: pabopto2bsdf writes the
# edges newest first and bsdf2ttree walks them as Radiance does (before: 27.7 % on patch 121).
# checkBSDF of Radiance's film tree (one transmission block): every line as Radiance's report,
# the Int->Ext Lambertian part (derived by reciprocity) included
if diff <(checkBSDF "$M/film_tb_g5_t90.xml" 2>/dev/null | sed 1,2d) <(sed 1,2d "$M/film_tb_g5_t90.checkBSDF.txt") > "$T/cbdiff"
then pass checkbsdf_report_film; else fail checkbsdf_report_film "$(head -4 "$T/cbdiff" | tr '\n' ' ')"; fi
if pabopto2bsdf "$T"/meas/film_tb/*.txt > "$T/film_tb.sir" 2> "$T/p2b.err" &&
   bsdf2ttree -g 5 -t 90 "$T/film_tb.sir" > "$T/film.xml" && checkBSDF "$T/film.xml" > "$T/film.cb" 2>/dev/null; then
    pass film_pipeline
    cbcmp checkbsdf_film_vs_radiance "$T/film.cb" "$M/film_tb_g5_t90.checkBSDF.txt" 1.0
    gzip -dc "$M/film_tb_g5_t90_klems_T.mtx.gz" > "$T/film_rad_T.mtx"
    bsdf2klems -n 1024 "$T/film.xml" > "$T/film_klems.xml" && rmtxop -fa "$T/film_klems.xml" > "$T/film_T.mtx"
    klems_cmp klems_T_film "$T/film_T.mtx" "$T/film_rad_T.mtx" 0.02
else
    fail film_pipeline "$(tail -2 "$T/p2b.err")"
fi

# the film's room-side reflection alone (film_rf: Radiance's film_g5_t98 "Interior Refl", -t 98):
# Lambertian part and largest directional value within 1 point of Radiance's report. The
# measurement grid is mirror-symmetric in phi, so two diagonals of a grid quadrilateral tie in
# the mesh and the rounding picks one; pabopto2bsdf computes the mesh in fused multiply-adds, as
# the reference's Radiance build (computed without: 34.4 % against 33.2 %, the walk then misses
# incidence 62-68 degrees, phi 270-315). Measured 33.0 % (0.2 point).
irefl() { awk -F'\t' '/^Interior Refl/ && /%/ {m=$4; gsub(/[ %]/, "", m); split($2, l, " "); print l[1], m; exit}' "$1"; }
if pabopto2bsdf "$T"/meas/film_rf/*.txt > "$T/film_rf.sir" 2> "$T/p2b_rf.err" &&
   bsdf2ttree -g 5 -t 98 "$T/film_rf.sir" > "$T/film_rf.xml" && checkBSDF "$T/film_rf.xml" > "$T/film_rf.cb" 2>/dev/null; then
    a=$(irefl "$T/film_rf.cb"); b=$(irefl "$M/film_g5_t98.checkBSDF.txt")
    if awk -v a="$a" -v b="$b" 'BEGIN {split(a, x, " "); split(b, y, " "); if (x[2] == "" || y[2] == "") exit 1
            for (i = 1; i <= 2; i++) {d = x[i] - y[i]; if (d < 0) d = -d; if (d > 1.0) exit 1}}'
    then pass checkbsdf_film_rf_vs_radiance; else fail checkbsdf_film_rf_vs_radiance "Interior Refl (Lambertian, max) $a vs Radiance's $b"; fi
else
    fail checkbsdf_film_rf_vs_radiance "$(tail -2 "$T/p2b_rf.err")"
fi

# 5. rttree_reduce against Radiance's on small grids (test/e2e/rttree_ref/MANIFEST.md)
D5=$(dirname "$0")/rttree_ref
X=$(dirname "$0")/ttree_expand.awk
awk -v n=2048 -f "$D5/grid.awk" > "$T/g3.txt"
awk -v n=4096 -f "$D5/grid.awk" > "$T/g4.txt"
# tree_eq NAME D G OURS RADIANCE : equal grids after expansion (1e-4 relative)
tree_eq() {
    r=$(paste <(awk -v D=$2 -v G=$3 -f "$X" "$4") <(awk -v D=$2 -v G=$3 -f "$X" "$5") |
        awk '{d=$1-$2; if(d<0)d=-d; m=$2<0?-$2:$2; if (d>1e-4*m+1e-9) bad++; n++} END {print n, bad+0; exit !(n == 2^('$2'*'$3') && bad == 0)}')
    if [ $? -eq 0 ]; then pass "$1"; else fail "$1" "cells / differing: $r"; fi
}
rttree_reduce -h -r 3 -g 4 -t 90 "$T/g3.txt" > "$T/r3.txt"
tree_eq rttree_reduce_r3 3 4 "$T/r3.txt" "$D5/r3_g4_t90.txt"
rttree_reduce -h -r 4 -g 3 -t 75 "$T/g4.txt" > "$T/r4.txt"
tree_eq rttree_reduce_r4 4 3 "$T/r4.txt" "$D5/r4_g3_t75.txt"
rttree_reduce -h -a -r 4 -g 3 -t 75 "$T/g4.txt" > "$T/r4a.txt"
tree_eq rttree_reduce_r4_recip 4 3 "$T/r4a.txt" "$D5/r4_g3_t75_a.txt"
# the comparison can fail: without -a the grid differs from the -a reference
if paste <(awk -v D=4 -v G=3 -f "$X" "$T/r4.txt") <(awk -v D=4 -v G=3 -f "$X" "$D5/r4_g3_t75_a.txt") |
    awk '{d=$1-$2; if(d<0)d=-d; if (d>1e-3) bad++} END {exit !(bad > 100)}'; then pass rttree_reduce_control
else fail rttree_reduce_control "the reciprocity-averaged reference does not differ from the plain grid"; fi

# 6. bad measurement files: the message names the file and line
G=$T/meas/fabric_tf/fabric_tf_t030_p000.txt
mkdir -p "$T/bad"
grep -v '^#format' "$G" > "$T/bad/nofmt.txt"
check_fails bad_no_format "nofmt.txt: no '#format" pabopto2bsdf "$T/bad/nofmt.txt" "$G"
grep -v '^#incident_angle' "$G" > "$T/bad/noangle.txt"
check_fails bad_no_angle "noangle.txt: no incident angle" pabopto2bsdf "$G" "$T/bad/noangle.txt"
awk 'NR==20 {$3="-0.25"} {print}' "$G" > "$T/bad/neg.txt"
check_fails bad_negative "neg.txt: line 20: negative" pabopto2bsdf "$T/bad/neg.txt" "$G"
{ cat "$G"; echo "85.000 10.000"; } > "$T/bad/trunc.txt"
check_fails bad_truncated "trunc.txt: line 2353: expected 3 numbers.*truncated" pabopto2bsdf "$T/bad/trunc.txt" "$G"
awk 'NR==30 {$1="60.000"} {print}' "$G" > "$T/bad/side.txt"
check_fails bad_wrong_side "side.txt: line 30: outgoing theta 60 is on the other side" pabopto2bsdf "$T/bad/side.txt" "$G"
sed 's/^#incident_angle 30 0/#incident_angle 200 0/' "$G" > "$T/bad/range.txt"
check_fails bad_angle_range "range.txt: line 3: incident angle theta 200" pabopto2bsdf "$T/bad/range.txt" "$G"
check_fails bad_mixed_sides "fabric_t._t(030|165)_p000.txt: incident theta (30|165) is on the other side" \
    pabopto2bsdf "$G" "$T/meas/fabric_tb/fabric_tb_t165_p000.txt"
awk 'NR==40 {$2="abc"} {print}' "$G" > "$T/bad/text.txt"
check_fails bad_text "text.txt: line 40: expected 3 numbers" pabopto2bsdf "$T/bad/text.txt" "$G"
check_fails bad_sir "not a BSDF interpolant|FORMAT" bsdf2ttree "$G"
head -c 3000 "$T/fabric_tb.sir" > "$T/bad/trunc.sir"
check_fails bad_sir_truncated "trunc.sir: byte [0-9]+: " bsdf2ttree "$T/bad/trunc.sir"
