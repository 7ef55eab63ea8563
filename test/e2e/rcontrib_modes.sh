# One rcontrib driver for both estimators (backward path walk and photon
# gather, -ap): every output feature works in both modes and writes the same
# headers — "!command" pipes (matrices and pictures), OpenEXR pictures,
# BigEndian= on binary matrices, the -x -y resolution line, and rcontrib's
# NCOMP/MODIFIER/BIN/NROWS/NCOLS lines.
. test/e2e/lib.sh
T=$(cd "$T" && pwd)
export SOURCE_DATE_EPOCH=1000000000
roofbox_suns > "$T/box.rad"
printf 'solar1\nsolar2\n' > "$T/mods.txt"
awk 'BEGIN{for(y=7;y>=0;y--) for(x=0;x<8;x++) printf "%.4f %.4f 0.001 0 0 1\n", (x+.5)/8, (y+.5)/8}' > "$T/grid.txt"
check map mkpmap -apC "$T/a.pm" 10k -apo port_m -apr 3 -n 1 "$T/box.rad"
# the header without its command line (the one line the two modes differ in)
# and FORMAT= (padded after it)
head_of() { getinfo "$1" | sed 1d | grep -v 'rcontrib \|FORMAT='; }
# the data after the header
data_of() { getinfo - < "$1"; }
# pixels of a picture, one a line
pixels() { pvalue -h -H -o -d "$1"; }

for mode in back pmap; do
    if [ $mode = back ]; then M="-I+ -ab 1 -ad 16"; else M="-I+ -ab -1 -ap $T/a.pm 60"; fi
    D="$T/$mode"
    mkdir -p "$D"
    rc() { rcontrib $M "$@" -M "$T/mods.txt" "$T/box.rad" < "$T/grid.txt"; }
    # matrices through a pipe: the data bytes of the file output
    check ${mode}_file rc -faf -x 8 -y 8 -o "$D/f_%s.mtx"
    check ${mode}_pipe rc -faf -x 8 -y 8 -o "!cat > $D/p_%s.mtx"
    ok=1
    for s in solar1 solar2; do cmp -s <(data_of "$D/f_$s.mtx") <(data_of "$D/p_$s.mtx") || ok=0; done
    if [ $ok = 1 ]; then pass ${mode}_pipe_same_bytes; else fail ${mode}_pipe_same_bytes; fi
    if grep -aq '^BigEndian=0$' "$D/f_solar1.mtx" && grep -aq '^-Y        8 +X        8$' "$D/f_solar1.mtx"; then
        pass ${mode}_bigendian_resolution
    else fail ${mode}_bigendian_resolution "$(head_of "$D/f_solar1.mtx" | tr '\n' '|')"; fi
    # pictures: RGBE files, RGBE through a pipe, OpenEXR with the same pixels
    check ${mode}_hdr rc -fac -x 8 -y 8 -o "$D/h_%s.hdr"
    check ${mode}_hdr_pipe rc -fac -x 8 -y 8 -o "!cat > $D/hp_%s.hdr"
    check ${mode}_exr rc -fac -x 8 -y 8 -o "$D/e_%s.exr"
    ok=1
    for s in solar1 solar2; do
        cmp -s <(data_of "$D/h_$s.hdr") <(data_of "$D/hp_$s.hdr") || ok=0
        exr2hdr "$D/e_$s.exr" "$D/c_$s.hdr" 2>/dev/null || ok=0
        [ "$(pixels "$D/h_$s.hdr" | md5sum)" = "$(pixels "$D/c_$s.hdr" | md5sum)" ] || ok=0
        [ -n "$(pixels "$D/h_$s.hdr" | awk '$1 > 0')" ] || ok=0   # not black
    done
    if [ $ok = 1 ]; then pass ${mode}_pictures_same; else fail ${mode}_pictures_same; fi
    if head -c 4 "$D/e_solar1.exr" | od -An -tx1 | grep -q '76 2f 31 01'; then pass ${mode}_exr_is_openexr
    else fail ${mode}_exr_is_openexr "$(head -c 16 "$D/e_solar1.exr" | od -An -c | head -1)"; fi
done
# the same header lines in both modes (matrices with -x -y, pictures)
for f in f_solar1.mtx h_solar2.hdr; do
    if [ "$(head_of "$T/back/$f")" = "$(head_of "$T/pmap/$f")" ]; then pass same_header_$f
    else fail same_header_$f "$(diff <(head_of "$T/back/$f") <(head_of "$T/pmap/$f") | tr '\n' '|')"; fi
done
# photon-map options are the option table's: @file, and -ab < 0 only with -ap
printf -- '-ab -1 -ap %s 60\n' "$T/a.pm" > "$T/pm.opt"
check atfile_pmap sh -c "rcontrib -h- -I+ @$T/pm.opt -fa -M $T/mods.txt $T/box.rad < $T/grid.txt > $T/at.txt"
check atfile_same sh -c "rcontrib -h- -I+ -ab -1 -ap $T/a.pm 60 -fa -M $T/mods.txt $T/box.rad < $T/grid.txt | cmp - $T/at.txt"
# -stats with -ap counts the photon gather's work (not the backward walk's
# zeros): one lookup point per -I+ ray, one lookup (-ab -1) or final gather
# (-ab 1) per point and source, the same with -n 2; the output unchanged
for ab in -1 1; do
    for n in 1 2; do
        rcontrib -h- -I+ -ab $ab -ad 16 -n $n -ap "$T/a.pm" 60 -stats -fa -M "$T/mods.txt" "$T/box.rad" \
            < "$T/grid.txt" > "$T/st$ab.$n.txt" 2> "$T/st$ab.$n.err"
    done
done
if grep -q '64 rays, 64 lookup points; 128 irradiance lookups (' "$T/st-1.1.err" &&
   grep -q '64 rays, 64 lookup points; 128 final gathers of 16 rays' "$T/st1.1.err" &&
   ! grep -q 'tracked direct sources' "$T/st-1.1.err" &&
   cmp -s "$T/st-1.1.err" "$T/st-1.2.err" && cmp -s "$T/st1.1.err" "$T/st1.2.err"; then pass pmap_stats_counts
else fail pmap_stats_counts "$(cat "$T/st-1.1.err" "$T/st1.1.err" | tr '\n' '|')"; fi
if cmp -s "$T/st-1.1.txt" "$T/at.txt"; then pass pmap_stats_output_unchanged; else fail pmap_stats_output_unchanged; fi
check_fails negative_ab_needs_map "needs a photon map" rcontrib -ab -1 -m solar1 "$T/box.rad" < "$T/grid.txt"
