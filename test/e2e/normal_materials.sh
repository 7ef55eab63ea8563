#!/bin/bash
# plastic, metal and trans (Radiance's normal.c model, shaded by scatter.c)
# against Radiance 6.1 values made beside the project (test/data/normalmat,
# commands in its MANIFEST.md): rough and pure sheets of each kind and two
# spheres under one distant source, seen from both sides.  At -ab 0 with
# -dj 0 Radiance is deterministic here (rough specular samples meet only
# the sky or the source, which they do not count), so rtrace and rcontrib
# must agree within 1e-4 relative; -ab 1 over a grey floor within the
# noise (4 %, see below).  Before scatter.c followed normal.c here, these failed:
# -ab 0 by a factor 15 where a rough transmitted sample met the source
# (Radiance counts that light by a Gaussian in the direct term), 100 %
# where it did not, 4 % on the metal sphere (the source's size widened the
# lobe of curved surfaces too), -ab 1 by 12 % (the rough transmission below
# -st was sampled instead of joining the diffuse transmission).
. test/e2e/lib.sh
M=test/data/normalmat
# cmp_rows A B FIRST LAST: max relative difference of rows FIRST..LAST
# (values of B at most 1e-9: the absolute difference counts)
cmp_rows() {
    paste "$1" "$2" | awk -v f="$3" -v l="$4" 'NR >= f && NR <= l {
        n = NF / 2; for (i = 1; i <= n; i++) { d = $i - $(i + n); if (d < 0) d = -d; m = $(i + n); if (m < 0) m = -m
            r = m > 1e-9 ? d / m : d; if (r > x) x = r } ; c++ }
        END { printf "%.3g", x; exit !(c == l - f + 1) }'
}
run() { name=$1 ref=$2 tol=$3 first=$4 last=$5; shift 5
    if "$@" > "$T/$name.txt" 2> "$T/$name.err"; then
        r=$(cmp_rows "$T/$name.txt" "$M/$ref" "$first" "$last")
        if [ $? = 0 ] && le "$r" "$tol"; then pass "$name"; else fail "$name" "max relative difference $r (tolerance $tol)"; fi
    else fail "$name" "$(head -2 "$T/$name.err")"; fi
}
# all 236 rays; the first 224 (sheets) where Radiance samples the rough
# trans sphere's inside (-st below its specular transmission) at random
run rtrace_ab0 rtrace_ab0_ref.txt 1e-4 1 236 rtrace -h -u- -ab 0 -dj 0 "$M/normalmat.rad" < "$M/probe.rays"
run rtrace_st_av rtrace_av_ref.txt 1e-4 1 224 rtrace -h -u- -ab 0 -dj 0 -st .01 -av .1 .2 .3 "$M/normalmat.rad" < "$M/probe.rays"
run rtrace_st_av_metal rtrace_av_ref.txt 1e-4 231 236 rtrace -h -u- -ab 0 -dj 0 -st .01 -av .1 .2 .3 "$M/normalmat.rad" < "$M/probe.rays"
run rcontrib_ab0 rcontrib_ab0_ref.txt 1e-4 1 224 rcontrib -h -ab 0 -dj 0 -m sunmat "$M/normalmat.rad" < "$M/probe.rays"
run rcontrib_ab0_metal rcontrib_ab0_ref.txt 1e-4 231 236 rcontrib -h -ab 0 -dj 0 -m sunmat "$M/normalmat.rad" < "$M/probe.rays"
# -ab 1: every row within 4 % of Radiance's single run.  Both sides are one
# noisy sample per row: on row 17 (the rough metal sphere, -ss 64) Radiance
# 6.1 gives 0.3144 ± 0.0026 (mean ± sd of 8 runs) and heliodon 0.3141 ±
# 0.0035 (6 seeds) while the reference holds 0.3170, so a 3 % bound on the
# largest of 64 differences failed by chance (-3.1 % after -ss followed
# Radiance's gaussamp; over all rows mean -0.05 %, rms 0.6 %).
run rtrace_ab1 rtrace_ab1_ref.txt 0.04 1 64 rtrace -h -ab 1 -ad 8192 -aa 0 -lw 1e-7 -ss 64 -dj 0 "$M/normalmat.rad" "$M/ground.rad" < "$M/above.rays"
# -oN is the surface's own normal (a cup's and a tube's point inwards), not
# turned towards the ray as -on is: hits on both sides of every kind
# (before, -oN printed the turned normal, the sign wrong on back hits)
run rtrace_oNn rtrace_oNn_ref.txt 1e-6 1 11 rtrace -h -oNn "$M/normals.rad" < "$M/normals.rays"
