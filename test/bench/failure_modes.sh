#!/usr/bin/env bash
# Where the methods fail (issue 19, item 5; docs/benchmarks/accuracy.md §6c), on the paper's office,
# view v2 (looking south at the facade), Chicago December 21 13:00 (DNI 700, DHI 80 W/m2: the sun
# 22° high, seen through wg1; the hour of test/e2e/stability_fs1g_sun.sh), gendaylit's exact sun and
# sky, every picture through pipeline/reference.sh stats (evalglare -d: E_v, median, mean, max
# luminance, DGP, DGI, glare-source solid angle).
#   sampling [RES]  the geometric FS1 (mat_fs1g: specular slats) and, when the tensor trees exist
#                   (CFS=dir), the data-driven FS1 rendered backward at RES (64) with k x k rays per
#                   pixel, k = 1 2 4 8 (rpict at k RES, pfilt -1 box filter to RES) and the geometric
#                   one at k = 16 as the reference (rpict -pj 1 -ab 1 -ad 64 -as 0 -aa 0 -lw 1e-3 -st 0:
#                   jittered rays, an unbiased estimate of each pixel's mean; -pj 0 at 1 ray per pixel
#                   is test/e2e/stability_fs1g_sun.sh's grid dependence)
#   photons         PM-CBDM's photon noise: the glass office, view v1, 32x32, 4 hours (the e2e site);
#                   PHOTONS 10k 30k 100k 300k, 4 seeds each (PM_SEED), E_v and DGP mean and spread
#   pixels          per-pixel photon noise: the sun part of one sunny hour (glass office, v1, 32x32),
#                   PHOTONS 10k and 100k, 4 seeds each; the relative spread per pixel by brightness class
#   blur            the 3PM's blurred sun: glass office, v2, the hour above, 64x64, pm/3pm/5pm (MF 6)
#                   and make reference (REF_OS 4, REF_OPTS -ab 1 -ad 256 unless set): the brightest glare source's luminance and solid
#                   angle of each method against the exact sun
# Usage (from the worktree, after make): test/bench/failure_modes.sh [PART [ARGS]] (no PART: all three,
# sampling at RES 32, as make bench runs it; about 40 min at load 20); output under
# build/bench/failure_modes.  Every timing with the load average.
set -eu
ROOT=$(pwd)
export PATH=$ROOT/${BUILD:-build}/bin:$PATH
R=$(mkdir -p "$ROOT/build/bench/failure_modes" && cd "$ROOT/build/bench/failure_modes" && pwd)
O=$ROOT/scenes/office
ST=$ROOT/pipeline/reference.sh
CFS=${CFS:-$ROOT/build/tmp/cfs_trees}
wea() { printf '%s\n' "place Chicago" "latitude 41.98" "longitude 87.92" "time_zone 90" "site_elevation 190" \
    "weather_data_file_units 1" "12 21 13.0 700 80" > "$1"; }
now() { date +%s.%N; }
el() { awk -v a="$1" -v b="$(now)" 'BEGIN{printf "%.1f", b - a}'; }
case ${1:-all} in
all) for p in "sampling 32" blur photons; do echo "== $p"; "$0" $p; done ;;
sampling)
    RES=${2:-64}
    gendaylit 12 21 13.0 -a 41.98 -o 87.92 -m 90 -W 700 80 > "$R/sky.rad"
    confs=fs1g; [ -r "$CFS/cfs1_ttree.xml" ] && [ -r "$CFS/cfs2_ttree.xml" ] && confs="fs1g fs1"
    export RAYPATH=".:$CFS"
    echo "| model | rays per pixel | E_v (lx) | L median | L mean | L max | DGP | DGI | omega (sr) | rpict (s) | load |"
    echo "|---|---|---|---|---|---|---|---|---|---|---|"
    for c in $confs; do
        (cd "$O" && oconv "mat_$c.rad" room.rad windows.rad "$R/sky.rad" skyglow.rad > "$R/$c.oct")
        ks="1 2 4 8"; [ "$c" = fs1g ] && ks="1 2 4 8 16"
        for k in $ks; do
            t0=$(now)
            (cd "$O" && nice rpict -vf v2.vf -x $((RES * k)) -y $((RES * k)) -ps 1 -pj 1 -dj 0 -ab 1 -ad 64 -as 0 -aa 0 -lw 1e-3 -st 0 "$R/$c.oct") |
                pfilt -1 -x "$RES" -y "$RES" > "$R/${c}_$k.hdr"
            t=$(el "$t0")
            set -- $("$ST" stats "$O/v2.vf" "$R/${c}_$k.hdr")
            printf '| %s | %d x %d | %.0f | %.0f | %.0f | %.3g | %.3f | %.1f | %.4f | %s | %s |\n' "$c" "$k" "$k" "$1" "$2" "$3" "$4" "$5" "$6" "$7" "$t" "$(cut -d' ' -f1 /proc/loadavg)"
        done
    done
    # the sun seen through the slats, converged: a 1.2-degree perspective view centred on gendaylit's sun
    # (240 x 240 jittered rays, -ab 0), its mean luminance times the view's solid angle and the cosine
    # to v2's direction (0 -1 0): the sun's share of E_v that the fisheye pictures hit or miss
    read -r dx dy dz < <(awk '$2 == "source" && $3 == "sun" {getline; getline; getline; print $2, $3, $4}' "$R/sky.rad")
    for c in $confs; do
        (cd "$O" && nice rpict -vtv -vp 1.8 3.8 1.2 -vd "$dx" "$dy" "$dz" -vu 0 0 1 -vh 1.2 -vv 1.2 -x 240 -y 240 -ps 1 -pj 1 -ab 0 -st 0 "$R/$c.oct") > "$R/${c}_sun.hdr"
        pvalue -h -H -b -d "$R/${c}_sun.hdr" | awk -v c="$c" -v dy="$dy" '{s += 179 * $1; n++} END {w = (1.2 * 3.14159265 / 180) ^ 2
            printf "%s: the sun through the slats (1.2-degree view, 240^2 rays): mean L %.4g cd/m2, E_v share %.0f lx\n", c, s / n, s / n * w * (-dy)}'
    done
    ;;
photons)
    . "$ROOT/test/e2e/lib.sh" 2>/dev/null || true
    printf '%s\n' "place Izmir_e2e" "latitude 38.4" "longitude -27.1" "time_zone -30" "site_elevation 25" "weather_data_file_units 1" \
        "3 21 10.5 820 110" "3 21 14.5 780 130" "12 21 12.5 60 180" "6 21 12.5 0 300" > "$R/iz.wea"
    P=$R/photons; A="WEATHER=$R/iz.wea OUT=$P CONFIG=glass VIEW=v1 RES=32 NPROC=2 MF=6"
    : > "$R/photons.txt"
    for n in 10k 30k 100k 300k; do
        for s in 1 2 3 4; do
            rm -rf "$P/sun.cpm" "$P/v1/dcsun" "$P/v1/annual.done" "$P/v1/annual.csv" "$P/v1/hours.log"
            t0=$(now)
            nice make -s -C "$O" $A PHOTONS=$n PM_SEED=$s "$P/v1/annual.done" > "$R/photons_make.log" 2>&1 || { tail -5 "$R/photons_make.log"; exit 1; }
            t=$(el "$t0")
            paste -d' ' <(grep -v '^#' "$P/v1/hours.log" | awk '{print $1}') <(tail -n +2 "$P/v1/annual.csv" | awk -F, '{print $2, $3}') |
                sed "s/^/$n $s $t /" >> "$R/photons.txt"
        done
    done
    echo "load after: $(cat /proc/loadavg)"
    echo "| photons | record | E_v mean (lx) | E_v spread (sd, %) | DGP mean | DGP sd | make (s, mean) |"
    echo "|---|---|---|---|---|---|---|"
    awk '{k = $1 " " $4; n[k]++; e[k] += $5; e2[k] += $5 * $5; g[k] += $6; g2[k] += $6 * $6; t[k] += $3}
        END {for (k in n) {split(k, a, " "); me = e[k] / n[k]; mg = g[k] / n[k]
            se = sqrt((e2[k] - n[k] * me * me) / (n[k] - 1)); sg = e2[k] >= 0 ? sqrt((g2[k] - n[k] * mg * mg) / (n[k] - 1)) : 0
            printf "| %s | %d | %.0f | %.1f | %.3f | %.4f | %.1f |\n", a[1], a[2], me, 100 * se / me, mg, sg, t[k] / n[k]}}' "$R/photons.txt" | sort -t'|' -k3,3n -k2,2g
    ;;
pixels)
    # per-pixel photon noise (the paper's §3.2): the sun part alone (pmcompose -s dcsun, the photon
    # map's term) of the hour Mar 21 10:30 (record 0 of the photons part's weather), glass office,
    # v1, 32x32, MF 6, PHOTONS 10k and 100k with 4 seeds each; per pixel the mean and the relative
    # sample standard deviation over the seeds; reported over the pixels lit by the sun part, in
    # three classes of their mean (the darkest third: where photon density is low)
    printf '%s\n' "place Izmir_e2e" "latitude 38.4" "longitude -27.1" "time_zone -30" "site_elevation 25" "weather_data_file_units 1" \
        "3 21 10.5 820 110" > "$R/px.wea"
    rm -f "$R/pixels.md"
    P=$R/pixels; A="WEATHER=$R/px.wea OUT=$P CONFIG=glass VIEW=v1 RES=32 NPROC=2 MF=6"
    echo "load before: $(cat /proc/loadavg)"
    for n in 10k 100k; do
        for s in 1 2 3 4; do
            rm -rf "$P/sun.cpm" "$P/v1/dcsun"
            nice make -s -C "$O" $A PHOTONS=$n PM_SEED=$s "$P/v1/dcsun" > "$R/pixels_make.log" 2>&1 || { tail -5 "$R/pixels_make.log"; exit 1; }
            pmcompose -n 2 -w "$R/px.wea" -vf "$O/v1.vf" -m 6 -s "$P/v1/dcsun/solar%d.hdr" -noglare -r 0 -I "$R/px_${n}_${s}_%d.hdr"
            pvalue -h -H -b -d "$R/px_${n}_${s}_0.hdr" | awk '{print 179 * $1}' > "$R/px_${n}_$s.txt"
        done
        grep "^mkpmap\|^rcontrib_sun" "$P/timings.txt" | tail -2 | tr '\n' ' '; echo "(PHOTONS=$n, last seed)"
        paste "$R/px_${n}_"[1-4].txt | awk -v n="$n" '{m = ($1 + $2 + $3 + $4) / 4; if (m <= 0) next; v = 0; for (i = 1; i <= 4; i++) v += ($i - m) ^ 2
            print m, sqrt(v / 3) / m}' | sort -g > "$R/px_$n.sd"
        k=$(wc -l < "$R/px_$n.sd")
        for c in 0 1 2; do
            a=$((c * k / 3 + 1)); b=$(((c + 1) * k / 3))
            sed -n "${a},${b}p" "$R/px_$n.sd" | sort -k2,2g | awk -v n="$n" -v c="$c" '{m[NR] = $1; r[NR] = $2; s += $2; if (!lo || $1 < lo) lo = $1; if ($1 > hi) hi = $1}
                END {printf "| %s | %s third (L %.3g-%.3g cd/m2) | %d | %.1f %% | %.1f %% | %.1f %% |\n", n, c == 0 ? "darkest" : (c == 1 ? "middle" : "brightest"),
                    lo, hi, NR, 100 * r[int(0.5 * NR) + 1], 100 * s / NR, 100 * r[int(0.95 * NR) + 1]}' >> "$R/pixels.md"
        done
    done
    echo "load after: $(cat /proc/loadavg)"
    echo "| photons | pixels (by mean sun-part luminance) | n | median rel. sd | mean rel. sd | p95 rel. sd |"
    echo "|---|---|---|---|---|---|"
    cat "$R/pixels.md"; rm -f "$R/pixels.md"
    ;;
blur)
    wea "$R/c.wea"
    B=$R/blur; A="WEATHER=$R/c.wea OUT=$B CONFIG=glass VIEW=v2 RES=64 NPROC=2 MF=6 KLEMS_WG1=glass"
    for m in pm 3pm 5pm; do
        t0=$(now); nice make -s -C "$O" $A METHOD=$m > "$R/blur_$m.log" 2>&1 || { tail -5 "$R/blur_$m.log"; exit 1; }
        echo "METHOD=$m: $(el "$t0") s, load $(cut -d' ' -f1 /proc/loadavg)"
    done
    t0=$(now); nice make -s -C "$O" $A REF_OS=4 REF_HOURS=0 REF_OPTS="${REF_OPTS:--ab 1 -ad 256 -as 0 -aa 0 -lw 1e-3 -st 0}" reference > "$R/blur_ref.log" 2>&1 || { tail -5 "$R/blur_ref.log"; exit 1; }
    echo "make reference: $(el "$t0") s, load $(cut -d' ' -f1 /proc/loadavg)"
    D=$B/compare/v2_ref
    cat "$D/table.csv"
    echo "| picture | sources | brightest source L (cd/m2) | its solid angle (sr) | L x omega | E_v,dir (lx) |"
    echo "|---|---|---|---|---|---|"
    for p in ref ref1 pm 3pm 5pm; do
        [ -s "$D/${p}_0.hdr" ] || continue
        evalglare -d -vf "$O/v2.vf" "$D/${p}_0.hdr" | awk -v p="$p" 'NR == 1 {n = $1} NR > 1 && $1 ~ /^[0-9]+$/ && NF > 10 {if ($5 > L) {L = $5; w = $6}}
            /^dgp,av_lum/ {split($0, a, ":"); split(a[2], v, " "); ed = v[5]}
            END {printf "| %s | %d | %.4g | %.3g | %.4g | %.0f |\n", p, n, L, w, L * w, ed}'
    done
    ;;
*) echo "usage: test/bench/failure_modes.sh sampling [RES] | photons | pixels | blur"; exit 1 ;;
esac
