#!/usr/bin/env bash
# Benchmark + full A4 check: contribution photon map of the reference box
# with the 145 MF:1 suns, 10M photons (mkpmap -apC ... 10m -apo glazing
# -apr 1 -n 2), then rcontrib -ap ... 1450 on the 28 sensors and on a
# 256x256 fisheye (per-sun DC images), folded with the Jan 1 10:30 sun
# vector (genskyvec -d -m 1 -5) and compared with the converged rtrace /
# rpict references for the sun at its patch centre.  Prints: stored
# photons/s, bytes per photon, sensor accuracy (mean |rel|, floor mean),
# fisheye E_v, gather time, peak RSS with a cache 10x smaller than the map.
# Figures go to docs/benchmarks/pmap.md.  NPHOT overrides the 10m count.
set -euo pipefail
BUILD=${BUILD:-build}
REF=${HELIODON_REF:-../shared/ref}
BOX=$REF/scenes/box
[ -f "$BOX/suns_mf1.rad" ] || { echo "SKIP: $BOX not found"; exit 0; }
BIN=$(cd "$BUILD/bin" && pwd)
W=$(mkdir -p "$BUILD/bench/pmap" && cd "$BUILD/bench/pmap" && pwd)
N=${NPHOT:-10m}
tm() { /usr/bin/time -f "%e %U %S %M" -o "$W/time.txt" "$@"; }
# Radiance's 10M map, one per Radiance build (an in-core and a PMAP_OOC
# build write different formats): named after RADIANCE_BIN's parent folder
RADPM=$W/rad_mf1_10M_$(basename "$(dirname "${RADIANCE_BIN:-none/bin}")").pm
echo "date: $(date -u '+%Y-%m-%d %H:%M') UTC, machine: $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
cd "$BOX"
# MODE=build: only the build speed, heliodon's mkpmap and (RADIANCE_BIN)
# Radiance's mkpmap alternately in the same run, REPS times each (BASEBIN=
# another heliodon bin directory adds it to the rotation, e.g. a build of
# main for before/after figures).  Prints stored photons per CPU-second and
# per wall second with the load average, and the same-run ratios.
if [ "${MODE:-}" = build ]; then
  RAD=${RADIANCE_BIN:-}
  [ -n "$RAD" ] && export RAYPATH=${RAYPATH:-.:$(dirname "$RAD")/lib}
  one() {  # label command...
    local label=$1; shift
    local l0; l0=$(cut -d' ' -f1 /proc/loadavg)
    tm "$@" 2> "$W/build.err" > /dev/null
    read -r wall user sys rss < "$W/time.txt"
    local st
    case $label in
      radiance) st=$(head -c 4096 "$W/rb.pm" | grep -a -m1 NumPhotons | awk '{print $3}') ;;
      *) st=$("$BIN/pmapdump" "$W/hb.pm" | awk '$1=="photons"{print $2}') ;;
    esac
    awk -v L="$label" -v s="$st" -v w="$wall" -v u="$user" -v y="$sys" -v r="$rss" -v l0="$l0" \
        -v l1="$(cut -d' ' -f1 /proc/loadavg)" 'BEGIN{
      printf "%-9s stored %9d  %7.2f s wall  %6.2f s CPU (%.2f user + %.2f sys)  %.3f M/CPU-s  %.3f M/s wall  RSS %d MB  load %s..%s\n",
             L, s, w, u + y, u, y, s / (u + y) / 1e6, s / w / 1e6, r / 1024, l0, l1 }' | tee -a "$W/build.txt"
  }
  : > "$W/build.txt"
  for rep in $(seq "${REPS:-2}"); do
    one heliodon "$BIN/mkpmap" -fo -apC "$W/hb.pm" "$N" -apo glazing -apr 1 -n 2 box_suns_mf1.oct
    if [ -n "${BASEBIN:-}" ]; then
      one base "$BASEBIN/mkpmap" -fo -apC "$W/hb.pm" "$N" -apo glazing -apr 1 -n 2 box_suns_mf1.oct
    fi
    if [ -n "$RAD" ] && [ -x "$RAD/mkpmap" ]; then
      rm -f "$W/rb.pm"
      one radiance "$RAD/mkpmap" -apC "$W/rb.pm" "$N" -apo glazing -apr 1 -n 2 box_suns_mf1.oct
    fi
  done
  awk '{c[$1]+=$7; w[$1]+=$4; s[$1]+=$3} END{
    for (k in c) printf "%-9s total: %.3f M stored per CPU-second, %.3f M stored/s wall\n", k, s[k]/c[k]/1e6, s[k]/w[k]/1e6;
    if (("radiance" in c) && ("heliodon" in c))
      printf "same-run ratio heliodon/Radiance: %.2fx per CPU-second, %.2fx per wall second (stored photons)\n",
             (s["heliodon"]/c["heliodon"])/(s["radiance"]/c["radiance"]), (s["heliodon"]/w["heliodon"])/(s["radiance"]/w["radiance"]);
    if (("base" in c) && ("heliodon" in c))
      printf "this build vs BASEBIN: %.2fx per CPU-second\n", (s["heliodon"]/c["heliodon"])/(s["base"]/c["base"]) }' "$W/build.txt"
  exit 0
fi
# MODE=gather: only the gather speed at RES^2 (default 256), rcontrib -ap with
# bandwidth 1450 on the 10M maps (built once into $W if absent: mf1.pm,
# and with RADIANCE_BIN $RADPM), heliodon / BASEBIN / Radiance
# alternately REPS times in the same run.  Prints CPU (user+sys) and wall
# per run with the load average, the means and the same-run ratios, and
# whether the pictures of BASEBIN and this build are identical (pvalue -d).
if [ "${MODE:-}" = gather ]; then
  RAD=${RADIANCE_BIN:-}
  [ -n "$RAD" ] && export RAYPATH=${RAYPATH:-.:$(dirname "$RAD")/lib}
  RES=${RES:-256}
  [ -f "$W/mf1.pm" ] || "$BIN/mkpmap" -fo -apC "$W/mf1.pm" "$N" -apo glazing -apr 1 -n 2 box_suns_mf1.oct 2> /dev/null
  if [ -n "$RAD" ] && [ -x "$RAD/rcontrib" ] && [ ! -f "$RADPM" ]; then
    "$RAD/mkpmap" -apC "$RADPM" 10m -apo glazing -apr 1 -n 2 box_suns_mf1.oct 2> /dev/null
  fi
  "$BIN/vwrays" -ff -x "$RES" -y "$RES" -vf fish.vf > "$W/grays.f"
  gone() {  # label command...
    local label=$1; shift
    local l0; l0=$(cut -d' ' -f1 /proc/loadavg)
    rm -rf "$W/g_$label"; mkdir -p "$W/g_$label"
    tm "$@" < "$W/grays.f" 2> /dev/null
    read -r wall user sys rss < "$W/time.txt"
    awk -v L="$label" -v w="$wall" -v u="$user" -v y="$sys" -v r="$rss" -v l0="$l0" \
        -v l1="$(cut -d' ' -f1 /proc/loadavg)" 'BEGIN{
      printf "%-9s %7.2f s wall  %6.2f s CPU (%.2f user + %.2f sys)  RSS %d MB  load %s..%s\n", L, w, u + y, u, y, r / 1024, l0, l1 }' |
      tee -a "$W/gather.txt"
  }
  hargs=(-ffc -x "$RES" -y "$RES" -ld- -ab -1 -n 2 -aC 20m)   # -o before -M: it applies to the modifiers after it
  : > "$W/gather.txt"
  for rep in $(seq "${REPS:-2}"); do
    gone heliodon "$BIN/rcontrib" "${hargs[@]}" -ap "$W/mf1.pm" 1450 -o "$W/g_heliodon/%s.hdr" -M mods_mf1.txt box_suns_mf1.oct
    if [ -n "${BASEBIN:-}" ]; then
      gone base "$BASEBIN/rcontrib" "${hargs[@]}" -ap "$W/mf1.pm" 1450 -o "$W/g_base/%s.hdr" -M mods_mf1.txt box_suns_mf1.oct
    fi
    if [ -n "$RAD" ] && [ -f "$RADPM" ]; then
      gone radiance "$RAD/rcontrib" -ffc -x "$RES" -y "$RES" -ld- -ab -1 -dj 0 -st 0 -lr 12 -n 2 \
        -ap "$RADPM" 1450 -o "$W/g_radiance/%s.hdr" -M mods_mf1.txt box_suns_mf1.oct
    fi
  done
  awk '{c[$1]+=$5; w[$1]+=$2; n[$1]++} END{
    for (k in c) printf "%-9s mean: %.2f s CPU, %.2f s wall (%d runs)\n", k, c[k]/n[k], w[k]/n[k], n[k];
    if (("radiance" in c) && ("heliodon" in c))
      printf "same-run ratio Radiance/heliodon: %.2fx by CPU, %.2fx by wall\n", (c["radiance"]/n["radiance"])/(c["heliodon"]/n["heliodon"]), (w["radiance"]/n["radiance"])/(w["heliodon"]/n["heliodon"]);
    if (("base" in c) && ("heliodon" in c))
      printf "this build vs BASEBIN: %.2fx less CPU, %.2fx less wall\n", (c["base"]/n["base"])/(c["heliodon"]/n["heliodon"]), (w["base"]/n["base"])/(w["heliodon"]/n["heliodon"]) }' "$W/gather.txt"
  if [ -n "${BASEBIN:-}" ]; then
    diff=$(for f in "$W"/g_heliodon/*.hdr; do
      a=$("$BIN/pvalue" -h -H -d "$f" | md5sum); b=$("$BIN/pvalue" -h -H -d "$W/g_base/$(basename "$f")" | md5sum)
      [ "$a" = "$b" ] || echo x; done | wc -l)
    echo "pictures whose pixels differ from BASEBIN's: $diff of $(ls "$W"/g_heliodon/*.hdr | wc -l)"
  fi
  exit 0
fi
tm "$BIN/mkpmap" -fo -v -apC "$W/mf1.pm" "$N" -apo glazing -apr 1 -n 2 box_suns_mf1.oct 2> "$W/mkpmap.err"
read -r wall user sys rss < "$W/time.txt"
grep "photons stored" "$W/mkpmap.err" || true
stored=$("$BIN/pmapdump" "$W/mf1.pm" | awk '$1=="photons"{print $2}')
bytes=$(stat -c %s "$W/mf1.pm")
awk -v s="$stored" -v w="$wall" -v u="$user" -v y="$sys" -v b="$bytes" -v r="$rss" 'BEGIN{
  printf "mkpmap: %d stored in %.2f s wall (%.2f s user + %.2f s sys), peak RSS %.0f MB\n", s, w, u, y, r/1024;
  printf "  stored photons/s: %.3f M/s wall, %.3f M per CPU-second (Radiance on this room: 0.115 M/s on 2 cores, 0.138 M per CPU-s)\n", s/w/1e6, s/(u+y)/1e6;
  printf "  bytes per stored photon on disk: %.2f (Radiance: 24 + primaries)\n", b/s }'
# sensors
tm "$BIN/rcontrib" -I+ -ab -1 -ap "$W/mf1.pm" 1450 -fa -y 28 -M mods_mf1.txt box_suns_mf1.oct < sensors.pts > "$W/sens.dc"
read -r wall user sys rss < "$W/time.txt"
echo "rcontrib -ap sensors (28 x 145): $wall s wall, $user s user"
"$BIN/dctimestep" "$W/sens.dc" a4_sunvec_mf1_0101_1030_noground.vec > "$W/sens.dat"
body() { awk 'b{print} /^$/{b=1}' "$1"; }
paste <(body "$W/sens.dat") <(body a4_res/patchsun_mf1_conv.dat) | head -25 | awk '
  {p=179*(.265*$1+.670*$2+.065*$3); r=179*(.265*$4+.670*$5+.065*$6); d=(p-r)/r; if(d<0)d=-d; s+=d; mp+=p; mr+=r}
  END{printf "A4 sensors (10M, bw 1450, folded): mean |rel| %.3f (required <= 0.20; Radiance 0.30-0.54), floor mean %.1f vs %.1f lux (%+.3f, required within 0.10)\n", s/25, mp/25, mr/25, mp/mr-1}'
# same without the exact direct term (Radiance semantics: direct through glass from the photons)
"$BIN/rcontrib" -I+ -ab -1 -apd- -ap "$W/mf1.pm" 1450 -fa -y 28 -M mods_mf1.txt box_suns_mf1.oct < sensors.pts > "$W/sens_pd.dc"
"$BIN/dctimestep" "$W/sens_pd.dc" a4_sunvec_mf1_0101_1030_noground.vec > "$W/sens_pd.dat"
paste <(body "$W/sens_pd.dat") <(body a4_res/patchsun_mf1_conv.dat) | head -25 | awk '
  {p=179*(.265*$1+.670*$2+.065*$3); r=179*(.265*$4+.670*$5+.065*$6); d=(p-r)/r; if(d<0)d=-d; s+=d; mp+=p; mr+=r}
  END{printf "  with -apd- (direct from photons, as Radiance): mean |rel| %.3f, floor mean %+.3f\n", s/25, mp/mr-1}'
# fisheye DC images, 256x256 and 128x128 (the reference rpict is 128x128);
# Radiance's rcontrib -ap on its own 10M map in the same run (RADIANCE_BIN)
RAD=${RADIANCE_BIN:-}
if [ -n "$RAD" ] && [ -x "$RAD/mkpmap" ]; then
  export RAYPATH=${RAYPATH:-.:$(dirname "$RAD")/lib}
  if [ ! -f "$RADPM" ]; then
    tm "$RAD/mkpmap" -apC "$RADPM" 10m -apo glazing -apr 1 -n 2 box_suns_mf1.oct 2> /dev/null
    read -r wall user sys rss < "$W/time.txt"
    echo "Radiance mkpmap 10m: $wall s wall, $user s user + $sys s sys, peak RSS $((rss / 1024)) MB"
  fi
fi
for res in 128 256; do
  rm -rf "$W/img$res"; mkdir -p "$W/img$res"
  "$BIN/vwrays" -ff -x $res -y $res -vf fish.vf > "$W/rays$res.f"
  tm "$BIN/rcontrib" -ffc -x $res -y $res -ld- -ab -1 -n 2 -ap "$W/mf1.pm" 1450 -aC 20m -o "$W/img$res/%s.hdr" \
     -M mods_mf1.txt box_suns_mf1.oct < "$W/rays$res.f"
  read -r wall user sys rss < "$W/time.txt"
  echo "rcontrib -ap ${res}x${res} fisheye DC (145 pictures): $wall s wall, $user s user, $sys s sys, peak RSS $((rss / 1024)) MB"
  hu=$user; hs=$sys; hw=$wall
  "$BIN/dctimestep" "$W/img$res/solar%d.hdr" a4_sunvec_mf1_0101_1030.vec > "$W/fold$res.hdr"
  if [ -n "$RAD" ] && [ -f "$RADPM" ]; then
    rm -rf "$W/rimg$res"; mkdir -p "$W/rimg$res"
    tm "$RAD/rcontrib" -ffc -x $res -y $res -ld- -ab -1 -dj 0 -st 0 -lr 12 -n 2 -ap "$RADPM" 1450 \
       -o "$W/rimg$res/%s.hdr" -M mods_mf1.txt box_suns_mf1.oct < "$W/rays$res.f" 2> /dev/null
    read -r wall user sys rss < "$W/time.txt"
    awk -v r=$res -v w=$wall -v u=$user -v s=$sys -v m=$rss -v hw=$hw -v hu=$hu -v hs=$hs 'BEGIN{
      printf "Radiance rcontrib -ap %dx%d (145 pictures): %.2f s wall, %.2f s user, %.2f s sys, peak RSS %d MB\n", r, r, w, u, s, m/1024;
      printf "  gather speed ratio heliodon/Radiance: %.2fx by CPU (user+sys), %.2fx by wall\n", (u+s)/(hu+hs), w/hw }'
  fi
done
ev=$("$BIN/evalglare" -V -vf fish.vf "$W/fold128.hdr")
evr=$("$BIN/evalglare" -V -vf fish.vf a4_res/ref_fish128_patchsun_mf1_0101_1030.hdr)
awk -v a="$ev" -v b="$evr" 'BEGIN{printf "fisheye E_v: %.1f lux vs rpict patch-centre reference %.1f lux (%+.3f, required within 0.03)\n", a, b, a/b-1}'
# bounded memory: cache of 1M photons (the map is ~10x larger); the decoded
# cache holds ~40 bytes per photon, so the requirement is RSS < cache + 300 MB
rm -rf "$W/img256s"; mkdir -p "$W/img256s"
tm "$BIN/rcontrib" -ffc -x 256 -y 256 -ld- -ab -1 -n 2 -ap "$W/mf1.pm" 1450 -aC 1m -o "$W/img256s/%s.hdr" \
   -M mods_mf1.txt box_suns_mf1.oct < "$W/rays256.f"
read -r wall user sys rss < "$W/time.txt"
same=$(for f in "$W"/img256/solar*.hdr; do
    a=$("$BIN/pvalue" -h -H -d "$f" | md5sum); b=$("$BIN/pvalue" -h -H -d "$W/img256s/$(basename "$f")" | md5sum)
    [ "$a" = "$b" ] || echo x; done | wc -l)
echo "256x256, cache 1M photons (map $stored): $wall s wall, $user s user, peak RSS $((rss / 1024)) MB (limit: cache ~40 MB + 300 MB); pictures whose pixels differ from the full-cache run: $same"
# optional large build under a memory budget: BIGN=100m (or 1g) BIGB=1500m
if [ -n "${BIGN:-}" ]; then
  BG="$W/big"; mkdir -p "$BG"; rm -f "$BG"/*.pm "$BG"/*.run*
  df -h "$BG" | tail -1
  ( while [ ! -f "$BG/done" ]; do du -sb "$BG" | cut -f1 >> "$BG/du.txt"; sleep 15; done ) &
  tm nice -n 5 "$BIN/mkpmap" -fo -v -apC "$BG/big.pm" "$BIGN" -apB "${BIGB:-1500m}" -apo glazing -apr 1 -n 2 \
     box_suns_mf1.oct 2> "$BG/mkpmap.err"
  touch "$BG/done"; wait
  read -r wall user sys rss < "$W/time.txt"
  grep "photons stored" "$BG/mkpmap.err" || true
  peak=$(sort -n "$BG/du.txt" | tail -1)
  echo "mkpmap $BIGN (-apB ${BIGB:-1500m}): $wall s wall, $user s user + $sys s sys, peak RSS $((rss / 1024)) MB, map $(stat -c %s "$BG/big.pm") bytes, peak disk (15 s samples) $peak bytes"
fi
