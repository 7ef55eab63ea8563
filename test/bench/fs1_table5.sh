#!/usr/bin/env bash
# FS1 data-driven against geometric at the hour of their largest disagreement (issue 19; the paper's
# §3.3.1-3.3.2, Table 5 rows 1-6; docs/benchmarks/accuracy.md §6f).
#   1. PM-CBDM over a year of weather for the office in FS1 data-driven (mat_fs1.rad: the CFS1/CFS2
#      tensor trees, CFS=dir) and FS1 geometric (mat_fs1g.rad: the slat arrays behind clear glass),
#      view v2, RES (32), suns on Reinhart MF:6 patches;
#   2. the hour of largest |DGP_geometric - DGP_data-driven| of the two annual.csv;
#   3. make reference in both run folders for that hour (REF_HOURS): gendaylit's exact sun and sky,
#      rpict REF_OPTS at REF_OS x RES with jittered rays box-filtered to RES, and once at one ray per
#      pixel centre; the same oversampled reference again with another seed (-seed 2) to show how far
#      it has converged; PM-CBDM's picture of the hour; evalglare statistics of every picture.
# Usage (from the worktree, after make): test/bench/fs1_table5.sh [RES [REF_OS [WEATHER [OUT]]]]
set -eu
ROOT=$(pwd)
export PATH=$ROOT/${BUILD:-build}/bin:$PATH
RES=${1:-32}
OS=${2:-8}
W=${3:-${HELIODON_REF:-$ROOT/../shared/ref}/weather/mannheim.epw}
R=$(mkdir -p "${4:-$ROOT/build/bench/fs1_table5_$RES}" && cd "${4:-$ROOT/build/bench/fs1_table5_$RES}" && pwd)
CFS=${CFS:-$ROOT/build/tmp/cfs_trees}
REF_OPTS=${REF_OPTS:--ab 2 -ad 64 -as 0 -aa 0 -lw 1e-4 -st 0}
ST=$ROOT/pipeline/reference.sh
O=$ROOT/scenes/office
if [ ! -s "$CFS/cfs1_ttree.xml" ] || [ ! -s "$CFS/cfs2_ttree.xml" ]; then
    mkdir -p "$CFS" && cp "$ROOT"/scenes/cfs/{Makefile,slats.awk,slat.mat} "$CFS"/
    nice make -s -C "$CFS" GENBSDF="$ROOT/${BUILD:-build}/bin/genBSDF" NPROC=2 TREE_C=500 cfs1_ttree.xml cfs2_ttree.xml
fi
cd "$O"
A="WEATHER=$W VIEW=v2 RES=$RES MF=6 NPROC=2 CFSDIR=$CFS"
for c in fs1 fs1g; do
    l0=$(cut -d' ' -f1-3 /proc/loadavg); t0=$(date +%s.%N)
    nice make -s $A CONFIG=$c OUT="$R/$c" > "$R/make_$c.log" 2>&1 || { tail -5 "$R/make_$c.log"; exit 1; }
    echo "PM-CBDM $c: $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.0f", b - a}') s wall, load $l0 -> $(cut -d' ' -f1-3 /proc/loadavg); $(tail -2 "$R/make_$c.log" | head -1)"
done
# record,month,day,hour,DGP data-driven,DGP geometric (annual.csv: record,Ev,DGP,DGI,...)
paste -d, <(grep -v '^#' "$R/fs1/v2/hours.log" | awk '{print $1 "," $2 "," $3 "," $4}') <(tail -n +2 "$R/fs1/v2/annual.csv" | cut -d, -f3) > "$R/dd.csv"
paste -d, <(grep -v '^#' "$R/fs1g/v2/hours.log" | awk '{print $1}') <(tail -n +2 "$R/fs1g/v2/annual.csv" | cut -d, -f3) > "$R/geo.csv"
awk -F, 'NR == FNR {g[$1] = $2; next} ($1 in g) {d = g[$1] - $5; print $0 "," g[$1] "," d}' "$R/geo.csv" "$R/dd.csv" > "$R/both.csv"
awk -F, '{d = $7 < 0 ? -$7 : $7; n++; s += d; if (d > 0.05) k++} END {printf "geometric vs data-driven (PM-CBDM): %d hours, mean |dDGP| %.4f, hours > 0.05: %d\n", n, s / n, k}' "$R/both.csv"
rec=$(sort -t, -k7,7g "$R/both.csv" | awk -F, '{d = $7 < 0 ? -$7 : $7; if (d > m) {m = d; r = $0}} END {print r}')
echo "largest disagreement: record,month,day,hour,DGP dd,DGP geo,geo-dd = $rec"
r=${rec%%,*}
echo "$r" > "$R/record.txt"
# 3. the reference for that hour in both run folders (make reference: REF_OS x RES jittered rays
#    box-filtered, and one ray per pixel centre; PM-CBDM's picture of the hour), then the oversampled
#    reference again with -seed 2 (the rpict of make reference is seeded 1)
export RAYPATH=".:$CFS"
echo "load before the references: $(cat /proc/loadavg)"
for c in fs1 fs1g; do
    D=$R/$c/compare/v2_ref
    l0=$(cut -d' ' -f1-3 /proc/loadavg); t0=$(date +%s.%N)
    nice make -s $A CONFIG=$c OUT="$R/$c" REF_HOURS="$r" REF_OS="$OS" REF_OPTS="$REF_OPTS" reference > "$R/ref_$c.log" 2>&1 || { tail -5 "$R/ref_$c.log"; exit 1; }
    echo "make reference $c: $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.0f", b - a}') s wall, load $l0 -> $(cut -d' ' -f1-3 /proc/loadavg); $(grep "^reference.*_v2_$r " "$R/$c/timings.txt" | tr '\n' ' ')"
    "$ST" sky "$r" "$R/$c/records.txt" "$R/$c/site.txt" > "$D/sky2_$r.rad"
    oconv "$R/$c/mat.rad" "$R/$c/scene/room.rad" "$R/$c/scene/ground.rad" "$R/$c/scene/win.rad" "$D/sky2_$r.rad" > "$D/ref2_$r.oct"
    # seeds 2..4 (seed 1 is make reference's)
    for sd in 2 3 4; do
        [ -s "$D/refs${sd}_$r.hdr" ] && continue
        [ "$c" = fs1g ] && [ "$sd" -gt 2 ] && continue   # the geometric model's seeds agree (below); the trees' do not
        /usr/bin/time -f "%U %S" -o "$D/seed$sd.time" sh -c "nice rpict -vf v2.vf -x $((RES * OS)) -y $((RES * OS)) -ps 1 -pj 1 -dj 0 $REF_OPTS -seed $sd $D/ref2_$r.oct |
            pfilt -1 -x $RES -y $RES > $D/refs${sd}_$r.hdr"
        echo "  seed $sd: $(awk '{printf "%.1f", $1 + $2}' "$D/seed$sd.time") s CPU"
    done
    rm -f "$D/ref2_$r.oct"
done
echo "load after: $(cat /proc/loadavg)"
echo "| model | picture | E_v (lx) | L median | L mean | L max | DGP | DGI | omega (sr) |"
echo "|---|---|---|---|---|---|---|---|---|"
for c in fs1 fs1g; do
    D=$R/$c/compare/v2_ref
    for p in ref refs2 refs3 refs4 ref1 pm; do
        case $p in ref) l="reference, ${OS}x$OS rays per pixel, seed 1";; refs?) l="reference, ${OS}x$OS rays per pixel, seed ${p#refs}";;
            ref1) l="reference, one ray per pixel";; pm) l="PM-CBDM";; esac
        [ -s "$D/${p}_$r.hdr" ] || continue
        set -- $("$ST" stats "$O/v2.vf" "$D/${p}_$r.hdr")
        printf '| %s | %s | %.0f | %.0f | %.0f | %.4g | %.3f | %.1f | %.4f |\n' "$c" "$l" "$1" "$2" "$3" "$4" "$5" "$6" "$7"
    done
done
# 4. the sun seen through the blinds, converged: a 1.2-degree perspective view from v2's eye centred
#    on gendaylit's sun (240 x 240 jittered rays, -ab 0), its mean luminance times the view's solid
#    angle and the cosine to v2's direction (0 -1 0): the sun's share of E_v, which the fisheye
#    pictures hit or miss with their rays per pixel
for c in fs1 fs1g; do
    D=$R/$c/compare/v2_ref
    read -r dx dy dz < <(awk '$2 == "source" && $3 == "sun" {getline; getline; getline; print $2, $3, $4}' "$D/sky2_$r.rad")
    oconv "$R/$c/mat.rad" "$R/$c/scene/room.rad" "$R/$c/scene/ground.rad" "$R/$c/scene/win.rad" "$D/sky2_$r.rad" > "$D/ref2_$r.oct"
    for sd in 1 2; do
        [ -s "$D/sun${sd}_$r.hdr" ] || nice rpict -vtv -vp 1.8 3.8 1.2 -vd "$dx" "$dy" "$dz" -vu 0 0 1 -vh 1.2 -vv 1.2 -x 240 -y 240 -ps 1 -pj 1 -ab 0 -st 0 -seed $sd "$D/ref2_$r.oct" > "$D/sun${sd}_$r.hdr"
        pvalue -h -H -b -d "$D/sun${sd}_$r.hdr" | awk -v c="$c" -v dy="$dy" -v sd="$sd" '{s += 179 * $1; n++} END {w = (1.2 * 3.14159265 / 180) ^ 2
            printf "%s: the sun through the blinds (1.2-degree view, 240^2 rays, -ab 0, seed %d): mean L %.4g cd/m2, E_v share %.0f lx\n", c, sd, s / n, s / n * w * (-dy)}'
    done
    rm -f "$D/ref2_$r.oct"
done
# 5. the geometric model's converged picture: the 8x8 reference (which misses the sun sliver between
#    the slats) plus the sun of the 1.2-degree view, box-filtered into the fisheye pixel that holds
#    the sun (its mean luminance times the 1.2-degree view's solid angle over the pixel's; evalglare
#    then finds it as the box filter of an unlimited oversampling would leave it)
D=$R/fs1g/compare/v2_ref
read -r dx dy dz < <(awk '$2 == "source" && $3 == "sun" {getline; getline; getline; print $2, $3, $4}' "$D/sky2_$r.rad")
Ls=$(pvalue -h -H -b -d "$D/sun1_$r.hdr" | awk '{s += $1; n++} END {printf "%.6g", s / n}')
# angular fisheye (-vta, 180 degrees, v2: direction 0 -1 0, up 0 0 1, right -1 0 0): the sun's pixel
read -r col row dL < <(awk -v x="$dx" -v y="$dy" -v z="$dz" -v n="$RES" -v L="$Ls" 'BEGIN {pi = 3.14159265358979; t = atan2(sqrt(x * x + z * z), -y)
    rr = t / (pi / 2) * n / 2; s = sqrt(x * x + z * z); u = -x / s; v = z / s
    c = int(n / 2 + rr * u); rw = int(n / 2 - rr * v)
    d = pi / n; om = d * d * (t > 0 ? sin(t) / t : 1); w = (1.2 * pi / 180) ^ 2
    printf "%d %d %.6g\n", c, rw, L * w / om}')
pvalue -h -H -d "$D/ref_$r.hdr" | awk -v c="$col" -v rw="$row" -v dl="$dL" -v n="$RES" 'NR - 1 == rw * n + c {$1 += dl; $2 += dl; $3 += dl} {print}' |
    pvalue -r -h -da -y "$RES" +x "$RES" > "$D/refc_$r.hdr"
set -- $("$ST" stats "$O/v2.vf" "$D/refc_$r.hdr")
echo "fs1g converged (8x8 reference + the sun in pixel col $col row $row, +$dL radiance): E_v $1 lx, L median $2, L mean $3, L max $4, DGP $5, DGI $6, omega $7"
