#!/usr/bin/env bash
# The paper's §3.3.5 setting (issue 19; docs/benchmarks/accuracy.md §6e): the office in FS2 (wg1 the
# CFS3 prismatic film, wg2 + wg3 the CFS4 fabric, static: mat_fs2_closed.rad, the tensor trees of
# scenes/cfs made by heliodon's genBSDF; the 3PM and 5PM with the Klems XMLs of scenes/cfs), view v2,
# a full year of weather, PM-CBDM, the 5PM, the plain 3PM and the imageless method (METHOD=imageless,
# dcglare semantics: the eye's illuminance DCs through the same trees) in one run folder, suns on
# Reinhart MF:6 patches for PM-CBDM and the 5PM alike; then "make compare" (p95 DGP of each, the
# hour-by-hour differences of every pair with their percentiles, the heat map of OUT/compare/index.html).
# The 5PM's sun part against the exact sun (PART sun, after PART year): three sunny hours of the
# run, one per season (the record of largest sun radiance times its incidence on the facade among
# the hours of Dec-Feb, Mar-May, Jun-Aug), the 5PM's term pmcompose -m 6 -s cds/solar%d.hdr alone, from
# the year's run (FIVE_OS=1) and from step 4 redone for the three hours' suns at FIVE_OS (default 4;
# OUT_os<K>sun, FIVE_SUNS), against the same definition rendered backward on the black scene with the
# window groups' BSDFs: rtrace -i -ab 1 -aa 0 -as 0 (no irradiance cache: the sun reaches the room
# only through the trees' sharp peaks; no super-sampling: rtrace's default -as is biased low where a
# few samples see a bright peak, accuracy.md §6f) times the reflectance map, plus rpict -ab 0 (the sun
# seen through the windows), at REF_OS x RES pixel centres box-filtered to RES (pfilt -1), with gendaylit's exact sun
# direction (seeds REF_SEEDS: their standard error is the reference's own noise) and with the 5PM's
# MF:6 patch direction (REF_MF_SEEDS: the part of the difference due to the sun's direction alone);
# REF_AD (-ad, default 128), REF_OS (4), REF_HI=1 adds one picture at 2 REF_OS, -ad REF_AD/4.
# E_v by evalglare -d, in total and for the interior and window terms apart.
# Usage (from the worktree, after make):
#   test/bench/methods_fs2.sh [year|sun] [RES [WEATHER [OUT]]]   (year, 64, the Mannheim EPW of the
#   reference data); OLD_WEATHER=1 FIVE_OS=4 REF_SEEDS=... REF_AD=... in the environment
# Each method's make is timed (wall) with the load average; OUT/timings.txt has wall and CPU per stage.
set -eu
ROOT=$(pwd)
export PATH=$ROOT/${BUILD:-build}/bin:$PATH
PART=${1:-year}
RES=${2:-64}
W=${3:-${HELIODON_REF:-$ROOT/../shared/ref}/weather/mannheim.epw}
R=$(mkdir -p "${4:-$ROOT/build/bench/methods_fs2_$RES}" && cd "${4:-$ROOT/build/bench/methods_fs2_$RES}" && pwd)
[ -r "$W" ] || { echo "methods_fs2: no weather file $W"; exit 1; }
C=$ROOT/scenes/cfs
# the film's tensor tree is not committed (6 MB): made here by heliodon's genBSDF (about 100 s CPU)
[ -s "$C/cfs3_ttree.xml" ] || nice make -s -C "$C" GENBSDF="$ROOT/${BUILD:-build}/bin/genBSDF" NPROC=2 cfs3_ttree.xml
# OLD_WEATHER=1: the weather file's timestamp is no reason to remake a run folder (make -o)
MO=${OLD_WEATHER:+-o $W}
# PM-CBDM's refined sun DC of the window pixels without -dn: with -dn 4 the film's tree peaks seen
# from the room after a diffuse bounce make a few suns' pictures 15-20 times their expectation
# (accuracy.md §6e, session 13); every sun at every vertex costs 12 times the stage's CPU here
A="WEATHER=$W OUT=$R CONFIG=fs2_closed VIEW=v2 RES=$RES MF=6 NPROC=2 CFSDIR=$C KLEMS_WG1=$C/cfs3_klems.xml KLEMS_WG2=$C/cfs4_klems.xml"
FS="FENSUN_OPTS=-ab 2 -ad 128 -lw 1e-4"
cd "$ROOT/scenes/office"
case $PART in
year)
for m in pm 3pm imageless 5pm; do
    l0=$(cut -d' ' -f1-3 /proc/loadavg); t0=$(date +%s.%N)
    nice make -s $MO $A "$FS" METHOD=$m > "$R/make_$m.log" 2>&1 || { tail -5 "$R/make_$m.log"; exit 1; }
    echo "METHOD=$m: $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN{printf "%.0f", b - a}') s wall, load $l0 -> $(cut -d' ' -f1-3 /proc/loadavg); $(tail -2 "$R/make_$m.log" | head -1)"
done
nice make -s $MO $A compare
echo "stages (wall s, CPU s):"
awk '{w += $2; c += $4; printf "  %s\n", $0} END {printf "  total %.0f s wall, %.0f s CPU\n", w, c}' "$R/timings.txt"
    ;;
sun)
    # the 5PM side: the year's run (FIVE_OS=1) and, in OUT_os<K>sun, step 4 alone for the three hours'
    # MF:6 suns at FIVE_OS=K (FIVE_SUNS), so that a high oversampling costs three suns, not 639
    K=${FIVE_OS:-4}; R4=${R}_os${K}sun
    S=$R/sun; mkdir -p "$S"; export RAYPATH=".:$C"
    [ -s "$R/v2/hours.log" ] && [ -s "$R/5pm/black.rad" ] && [ -s "$R/5pm/mapb.oct" ] || { echo "methods_fs2 sun: run the year part first ($R)"; exit 1; }
    nice make -s $MO $A "$R/records.txt" "$R/site.txt"
    read -r lat lon mer < "$R/site.txt"
    # E_v of a picture scaled by $2 (evalglare -d prints two significant digits for unit-radiance suns)
    ev() { pcomb -s "${2:-1}" "$1" | evalglare -d -vf v2.vf 2>/dev/null | awk -F: '/^dgp,av_lum,E_v/ {split($2, v, " "); print v[3]}'; }
    # the three hours: per season the largest sun radiance x incidence on the facade (-dy: the facade
    # faces -y) among hours with a sun patch; PM-CBDM's hour log (the same MF:6 suns and sun vectors
    # as the 5PM's), so that the references can start before the 5PM's step 4 is done
    recs=$(grep -v '^#' "$R/v2/hours.log" | awk '$5 > 0 && $7 < 0 {s = ($2 == 12 || $2 <= 2) ? 1 : ($2 <= 5 ? 2 : ($2 <= 8 ? 3 : 0))
        if (!s) next; v = -$7 * $9; if (v > b[s]) {b[s] = v; r[s] = $1}} END {print r[1], r[2], r[3]}')
    pats=$(for r in $recs; do awk -v r="$r" '$1 == r {print $5}' "$R/v2/hours.log"; done | tr '\n' ' ')
    echo "load before: $(cat /proc/loadavg); records $recs; MF:6 patches $pats"
    ( l0=$(cut -d' ' -f1-3 /proc/loadavg); t0=$(date +%s)
      nice make -s $MO ${A/OUT=$R/OUT=$R4} METHOD=5pm FIVE_OS="$K" FIVE_SUNS="$pats" "$R4/5pm/v2/cds" > "$S/make_os$K.log" 2>&1 || { tail -5 "$S/make_os$K.log"; exit 1; }
      echo "5PM step 4 at FIVE_OS=$K for the three suns: $(( $(date +%s) - t0 )) s wall, load $l0 -> $(cut -d' ' -f1-3 /proc/loadavg)"
      grep 5pm_ "$R4/timings.txt" | sed 's/^/  /' ) &
    mk_map() {   # reflectance map at $1 x $1 (the 5PM's step 2)
        [ -s "$S/map_$1.hdr" ] && return
        rpict -vf v2.vf -x "$1" -y "$1" -ps 1 -pj 0 -dj 0 -ab 0 -av 0.3183099 0.3183099 0.3183099 "$R/mask.oct" > "$S/ma_$1.hdr"
        rpict -vf v2.vf -x "$1" -y "$1" -ps 1 -pj 0 -dj 0 -ab 0 -av 0.3183099 0.3183099 0.3183099 "$R/5pm/mapb.oct" > "$S/mb_$1.hdr"
        pcomb -e 'ro=ri(1)-ri(2);go=gi(1)-gi(2);bo=bi(1)-bi(2)' -o "$S/ma_$1.hdr" -o "$S/mb_$1.hdr" > "$S/map_$1.hdr"
    }
    # ref TAG OS AD SEED: the sun part rendered backward on the black scene with the sun of xsun_TAG.oct
    # (TAG = record: gendaylit's exact direction; TAG = record_mf: the 5PM's patch centre), at OS x RES
    # pixel centres box-filtered to RES: the interior term rtrace -i -ab 1 -ad AD -aa 0 -as 0 (no irradiance
    # cache: the sun reaches the room only through the trees' sharp peaks, which a cache interpolates
    # wrongly; no super-sampling, biased low there) times the map -> ${f}_i.hdr; the window term
    # rpict -ab 0 -> ${f}_l.hdr; their sum ${f}.hdr
    ref() {
        local n=$((RES * $2)) f=$S/ref_$1_$2_$3_$4
        [ -s "$f.hdr" ] && return
        mk_map "$n"
        /usr/bin/time -f "%U %S" -o "$f.cpu" sh -c "vwrays -ff -vf v2.vf -x $n -y $n | nice rtrace -h -ff -i -ab 1 -ad $3 -aa 0 -as 0 -lw 1e-5 -dj 0 -av 0 0 0 -seed $4 -n 2 $S/xsun_$1.oct |
            pvalue -r -h -df -y $n +x $n > $f.ri.hdr && nice rpict -vf v2.vf -x $n -y $n -ps 1 -pj 0 -dj 0 -ab 0 -av 0 0 0 -seed $4 $S/xsun_$1.oct > $f.rl.hdr"
        pcomb -e 'ro=ri(1)*ri(2);go=gi(1)*gi(2);bo=bi(1)*bi(2)' -o "$S/map_$n.hdr" -o "$f.ri.hdr" | pfilt -1 -x "$RES" -y "$RES" > "$f"_i.hdr
        pfilt -1 -x "$RES" -y "$RES" "$f.rl.hdr" > "$f"_l.hdr
        pcomb -e 'ro=ri(1)+ri(2);go=gi(1)+gi(2);bo=bi(1)+bi(2)' -o "$f"_i.hdr -o "$f"_l.hdr > "$f.hdr"
        rm -f "$f.ri.hdr" "$f.rl.hdr"
    }
    # REF_SEEDS: the exact sun's seeds; REF_MF_SEEDS: the 5PM's patch direction; REF_HI=1: one more
    # picture at twice the oversampling and a quarter of -ad (the same rays: pixel convergence)
    # refl TAG OS: the window term alone (rpict -ab 0: cheap) at OS x RES, box-filtered to RES: whether
    # the sun seen through the film is converged in pixel sampling
    refl() {
        local n=$((RES * $2)) f=$S/refl_$1_$2
        [ -s "$f.hdr" ] && return
        /usr/bin/time -f "%U %S" -o "$f.cpu" sh -c "nice rpict -vf v2.vf -x $n -y $n -ps 1 -pj 0 -dj 0 -ab 0 -av 0 0 0 -seed 1 $S/xsun_$1.oct > $f.rl.hdr"
        pfilt -1 -x "$RES" -y "$RES" "$f.rl.hdr" > "$f.hdr" && rm -f "$f.rl.hdr"
    }
    RS=${REF_SEEDS:-1 2}; MS=${REF_MF_SEEDS:-1}; AD=${REF_AD:-128}; OS=${REF_OS:-4}; HI=${REF_HI:-0}; LOS=${REF_LOS:-16}
    for r in $recs; do
        read -r mo da hr p dx dy dz sr sg sb < <(awk -v r="$r" '$1 == r {print $2, $3, $4, $5, $6, $7, $8, $9, $10, $11}' "$R/v2/hours.log")
        read -r dni dhi < <(awk -v r="$r" '$1 == r {print $5, $6}' "$R/records.txt")
        d=$(gendaylit "$mo" "$da" "$hr" -a "$lat" -o "$lon" -m "$mer" -W "$dni" "$dhi" | awk '$2 == "source" && $3 == "sun" {getline; getline; getline; print $2, $3, $4}')
        # the sun radiance is 1 in the references; E_v is scaled by the hour's (sr) afterwards
        printf 'void light xsun 0 0 3 1 1 1\nxsun source sun 0 0 4 %s 0.533\n' "$d" > "$S/xsun_$r.rad"
        printf 'void light xsun 0 0 3 1 1 1\nxsun source sun 0 0 4 %s %s %s 0.533\n' "$dx" "$dy" "$dz" > "$S/xsun_${r}_mf.rad"
        for t in "$r" "${r}_mf"; do oconv "$R/mat.rad" "$R/5pm/black.rad" "$R/scene/win.rad" "$S/xsun_$t.rad" > "$S/xsun_$t.oct"; done
        echo "$r $mo $da $hr $p $sr $d" > "$S/hour_$r.txt"
        for sd in $RS; do ref "$r" "$OS" "$AD" "$sd"; done
        for sd in $MS; do ref "${r}_mf" "$OS" "$AD" "$sd"; done
        [ "$HI" = 0 ] || ref "$r" $((OS * 2)) $((AD / 4)) 1
        refl "$r" "$LOS"; refl "${r}_mf" "$LOS"
        echo "record $r: references done, load $(cut -d' ' -f1-3 /proc/loadavg)"
    done
    wait
    # per picture set: E_v total / interior / window, the seeds' mean and standard error
    stats() { awk '{n++; for (k = 1; k <= 3; k++) {s[k] += $k; q[k] += $k * $k}} END {for (k = 1; k <= 3; k++) {m = s[k] / n
        se = n > 1 ? sqrt((q[k] - n * m * m) / (n - 1) / n) : 0; printf "%.1f %.1f ", m, se}}'; }
    evs() { local f; for f in "$@"; do echo "$(ev "$f.hdr" "$SR") $(ev "${f}_i.hdr" "$SR") $(ev "${f}_l.hdr" "$SR")"; done; }
    echo "E_v (lx) total / interior term / sun seen through the windows; references at OS $OS, -ad $AD, -aa 0: mean ± standard error over seeds $RS (exact sun), $MS (MF:6 sun)"
    echo "| hour | reference, exact sun | the same, OS $((OS * 2)) -ad $((AD / 4)) | reference, the 5PM's MF:6 sun | window term at OS $LOS: exact / MF:6 sun | 5PM FIVE_OS=1 (year run) | 5PM FIVE_OS=$K | 5PM FIVE_OS=$K vs exact / vs MF:6 | reference CPU s |"
    echo "|---|---|---|---|---|---|---|---|---|"
    for r in $recs; do
        read -r _ mo da hr p SR d < "$S/hour_$r.txt"
        e=$(for sd in $RS; do evs "$S/ref_${r}_${OS}_${AD}_$sd"; done | stats)
        m=$(for sd in $MS; do evs "$S/ref_${r}_mf_${OS}_${AD}_$sd"; done | stats)
        h="- - -"; [ "$HI" = 0 ] || h=$(evs "$S/ref_${r}_$((OS * 2))_$((AD / 4))_1")
        wl="$(ev "$S/refl_${r}_$LOS.hdr" "$SR") $(ev "$S/refl_${r}_mf_$LOS.hdr" "$SR")"
        five() {   # five DIR OS: the 5PM's sun part of patch p, its interior term and window term
            local c=$1/solar$p.hdr
            [ -s "$c" ] || { echo "- - -"; return; }
            pmcompose -n 2 -w "$W" -vf v2.vf -m 6 -s "$1/solar%d.hdr" -noglare -r "$r" -I "$S/sun5_$2_%d.hdr"
            if [ "$2" = 1 ]; then mp=$R/5pm/v2/map.hdr; else mp=$R4/5pm/v2/os/map.hdr; fi
            pcomb -e 'ro=ri(1)*ri(2);go=gi(1)*gi(2);bo=bi(1)*bi(2)' -o "$mp" -o "${1%/cds}/cdsi/solar$p.hdr" | pfilt -1 -x "$RES" -y "$RES" > "$S/sun5_$2_${r}_i.hdr"
            pfilt -1 -x "$RES" -y "$RES" "${1%/cds}/cdsl/solar$p.hdr" > "$S/sun5_$2_${r}_l.hdr"
            echo "$(ev "$S/sun5_$2_$r.hdr") $(ev "$S/sun5_$2_${r}_i.hdr" "$SR") $(ev "$S/sun5_$2_${r}_l.hdr" "$SR")"
        }
        f1=$(five "$R/5pm/v2/cds" 1); fk=$(five "$R4/5pm/v2/cds" "$K")
        t=$(cat "$S/ref_${r}_"*.cpu "$S/refl_${r}_"*.cpu | awk '{s += $1 + $2} END {printf "%.0f", s}')
        awk -v m="$mo" -v d="$da" -v h="$hr" -v e="$e" -v mf="$m" -v hi="$h" -v wl="$wl" -v f1="$f1" -v fk="$fk" -v t="$t" -v nm="$(echo $MS | wc -w)" '
            function g(v) {return v == "-" ? "-" : sprintf("%.0f", v)}
            BEGIN {
            split(e, E, " "); split(mf, M, " "); split(hi, H, " "); split(f1, A, " "); split(fk, B, " ")
            x = (B[1] > 0) ? 100 * (B[1] / E[1] - 1) : 0; y = (B[1] > 0) ? 100 * (B[1] / M[1] - 1) : 0
            split(wl, L, " ")
            mm = nm > 1 ? sprintf("%.0f ± %.0f / %.0f ± %.0f / %.0f ± %.0f", M[1], M[2], M[3], M[4], M[5], M[6]) : sprintf("%.0f / %.0f / %.0f", M[1], M[3], M[5])
            printf "| %d/%d %.2f h | %.0f ± %.0f / %.0f ± %.0f / %.0f ± %.0f | %s / %s / %s | %s | %s / %s | %s / %s / %s | %s / %s / %s | %+.1f %% / %+.1f %% | %s |\n",
                m, d, h, E[1], E[2], E[3], E[4], E[5], E[6], g(H[1]), g(H[2]), g(H[3]), mm, g(L[1]), g(L[2]),
                g(A[1]), g(A[2]), g(A[3]), g(B[1]), g(B[2]), g(B[3]), x, y, t}'
    done
    echo "load after: $(cat /proc/loadavg)"
    ;;
*) echo "usage: test/bench/methods_fs2.sh [year|sun] [RES [WEATHER [OUT]]]"; exit 1 ;;
esac
