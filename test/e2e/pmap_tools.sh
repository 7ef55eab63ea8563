# mkpmap / pmapdump / rcontrib -ap end to end on a small analytic box.
. test/e2e/lib.sh

# black box with a glazed roof opening (port) and a grey floor; one sun overhead
roofbox_suns > "$T/box.rad"
printf 'solar1\nsolar2\n' > "$T/mods.txt"
# the binary part of a map (after the text header, which holds the command line)
body() { off=$(grep -abo -m1 'FORMAT=heliodon_contrib_pmap' "$1" | cut -d: -f1); tail -c +$((off + 30)) "$1"; }
same_body() { body "$1" > "$T/body1"; body "$2" > "$T/body2"; [ -s "$T/body1" ] && cmp "$T/body1" "$T/body2"; }

check build mkpmap -apC "$T/a.pm" 40k -apo port_m -apr 3 -n 1 "$T/box.rad"
check build_n2 mkpmap -apC "$T/b.pm" 40k -apo port_m -apr 3 -n 2 "$T/box.rad"
check threads_identical same_body "$T/a.pm" "$T/b.pm"
check extsort mkpmap -apC "$T/c.pm" 40k -apo port_m -apr 3 -n 2 -apB 100k "$T/box.rad"
check extsort_identical same_body "$T/a.pm" "$T/c.pm"
# emission shards (sources split over runs) merge into the single-run map
check shard0 mkpmap -apC "$T/s0.pm" 40k -apo port_m -apr 3 -apH 0 2 "$T/box.rad"
check shard1 mkpmap -apC "$T/s1.pm" 40k -apo port_m -apr 3 -apH 1 2 "$T/box.rad"
check shard_merge mkpmap -apJ "$T/sm.pm" "$T/s0.pm" "$T/s1.pm"
check shards_identical same_body "$T/a.pm" "$T/sm.pm"
check_fails shard_twice "given twice|traced in both" mkpmap -fo -apJ "$T/sm.pm" "$T/s0.pm" "$T/s0.pm"
check_fails bad_shard "shard k of n" mkpmap -apC "$T/x.pm" 40k -apo port_m -apH 2 2 "$T/box.rad"
check_fails no_clobber "exists" mkpmap -apC "$T/a.pm" 40k -apo port_m "$T/box.rad"
check clobber mkpmap -fo -apC "$T/a.pm" 40k -apo port_m -apr 3 "$T/box.rad"
# options from an @file (the option table's expansion, as the other programs)
printf '%s\n' '# ports and seed' '-apo port_m' '-apr 3 -n 2' > "$T/mk.opt"
check atfile mkpmap -apC "$T/f.pm" 40k @"$T/mk.opt" "$T/box.rad"
check atfile_identical same_body "$T/a.pm" "$T/f.pm"
if grep -aq -- "-apC $T/f.pm 40k -apo port_m -apr 3 -n 2 " "$T/f.pm"; then pass atfile_header
else fail atfile_header "$(grep -a mkpmap "$T/f.pm" | head -1)"; fi
check_fails bad_orient "expected -apo, -apo\+" mkpmap -apC "$T/x.pm" 10k -apoX port_m "$T/box.rad"

# pmapdump: header, count within 5 % of the asked 40k, page check
if pmapdump -c -s "$T/a.pm" > "$T/dump.txt" 2>&1; then
    n=$(awk '$1=="photons"{print $2}' "$T/dump.txt")
    if grep -q "FORMAT=heliodon_contrib_pmap" "$T/dump.txt" && grep -q "^check" "$T/dump.txt" && close "$n" 40000 0.05
    then pass pmapdump; else fail pmapdump "photons=$n"; fi
else fail pmapdump "$(head -2 "$T/dump.txt")"; fi

# corrupt and truncated maps
size=$(stat -c %s "$T/a.pm")
cp "$T/a.pm" "$T/bad.pm"
printf '\377\377\377\377' | dd of="$T/bad.pm" bs=1 seek=$((size / 2)) conv=notrunc 2>/dev/null
check_fails corrupt_page "checksum|decompress" pmapdump -c "$T/bad.pm"
head -c $((size - 100)) "$T/a.pm" > "$T/trunc.pm"
check_fails truncated "truncated" pmapdump "$T/trunc.pm"
check_fails not_a_map "not a photon map|FORMAT" pmapdump "$T/box.rad"

# bad options
check_fails global_map "only contribution" mkpmap -apg "$T/x.pm" 10k "$T/box.rad"
check_fails no_port "port" mkpmap -apC "$T/x.pm" 10k "$T/box.rad"
check_fails unknown_port "nosuch" mkpmap -apC "$T/x.pm" 10k -apo nosuch "$T/box.rad"
check_fails antimatter "not supported" mkpmap -apC "$T/x.pm" 10k -apo port_m -aps foo "$T/box.rad"
check_fails bad_count "photon count" mkpmap -apC "$T/x.pm" lots -apo port_m "$T/box.rad"

# rcontrib -ap -ab -1 -I+: floor centre under sun1 = Omega * T(0) * 1e6 (+ a little
# interreflection off the glass); -V- coefficients = that / 1e6
printf '0.5 0.5 0.001 0 0 1\n0.1 0.1 0.001 0 0 1\n0.5 0.6 0.001 0 0 1\n0.3 0.4 0.001 0 0 1\n' > "$T/pts.txt"
if rcontrib -I+ -ab -1 -ap "$T/a.pm" 60 -fa -y 4 -M "$T/mods.txt" "$T/box.rad" < "$T/pts.txt" > "$T/dc.txt" 2>"$T/rc.err"; then
    v=$(data_values "$T/dc.txt" | sed -n 2p)
    # exact: 2 pi (1 - cos(0.2665 deg)) * T(normal) with T from the glass formula (tn = .96) = 5.991e-05
    if close "$v" 5.991e-05 0.05; then pass rcontrib_ap_value; else fail rcontrib_ap_value "got $v"; fi
else fail rcontrib_ap_value "$(head -2 "$T/rc.err")"; fi
# record ranges assemble into the full result
rcontrib -h- -I+ -ab -1 -ap "$T/a.pm" 60 -fa -y 4 -apR 0 2 -M "$T/mods.txt" "$T/box.rad" < "$T/pts.txt" > "$T/r1.txt" 2>/dev/null
rcontrib -h- -I+ -ab -1 -ap "$T/a.pm" 60 -fa -y 4 -R 2 2 -M "$T/mods.txt" "$T/box.rad" < "$T/pts.txt" > "$T/r2.txt" 2>/dev/null
rcontrib -h- -I+ -ab -1 -ap "$T/a.pm" 60 -fa -M "$T/mods.txt" "$T/box.rad" < "$T/pts.txt" > "$T/rall.txt" 2>/dev/null
if [ -s "$T/rall.txt" ] && cat "$T/r1.txt" "$T/r2.txt" | cmp -s - "$T/rall.txt"; then pass row_ranges; else fail row_ranges; fi
# a small page cache gives the same numbers as the whole map in memory
rcontrib -h- -I+ -ab -1 -ap "$T/a.pm" 60 -aC 1k -fa -M "$T/mods.txt" "$T/box.rad" < "$T/pts.txt" > "$T/rsmall.txt" 2>/dev/null
if [ -s "$T/rsmall.txt" ] && cmp -s "$T/rsmall.txt" "$T/rall.txt"; then pass cache_identical; else fail cache_identical; fi
check_fails rcontrib_not_source "not a light source" rcontrib -I+ -ab -1 -ap "$T/a.pm" 60 -m port_m "$T/box.rad" < "$T/pts.txt"
check_fails rcontrib_bad_map "cannot open" rcontrib -I+ -ab -1 -ap "$T/none.pm" 60 -M "$T/mods.txt" "$T/box.rad" < "$T/pts.txt"
# direction bins (reinhart.cal, MF:1): the sun overhead lands in the zenith bin 145,
# both as the exact direct term and as direct photons (-apd-); the bins sum to the total
printf '0.5 0.5 0.001 0 0 1\n' > "$T/p1.txt"
for mode in -apd+ -apd-; do
    rcontrib -h- -I+ -ab -1 $mode -ap "$T/a.pm" 60 -fa -m solar1 "$T/box.rad" < "$T/p1.txt" > "$T/tot.txt" 2>/dev/null
    rcontrib -h- -I+ -ab -1 $mode -ap "$T/a.pm" 60 -fa -e MF:1 -f reinhart.cal -b rbin -bn Nrbins -m solar1 \
        "$T/box.rad" < "$T/p1.txt" > "$T/bins.txt" 2>/dev/null
    tot=$(awk '{print $2}' "$T/tot.txt")
    read -r nb z s < <(awk '{s=0; for(i=2;i<=NF;i+=3) s+=$i; print NF/3, $(145*3+2), s}' "$T/bins.txt")
    if [ "$nb" = 146 ] && close "$s" "$tot" 1e-5 && close "$z" "$tot" 0.02; then pass "direction_bins$mode"
    else fail "direction_bins$mode" "bins=$nb zenith=$z sum=$s total=$tot"; fi
done

# ---- output side: per-bin (%d) and per-modifier (%s) files, pictures (RGBE and EXR), -t ----
# per-bin files hold the same numbers as the columns of one matrix
rcontrib -h- -I+ -ab -1 -apd- -ap "$T/a.pm" 60 -fa -e MF:1 -f reinhart.cal -b rbin -bn Nrbins -o "$T/pb%03d.txt" \
    -m solar1 "$T/box.rad" < "$T/p1.txt" 2>/dev/null
nfiles=$(ls "$T"/pb*.txt 2>/dev/null | wc -l)
if [ "$nfiles" = 146 ] && [ "$(cat "$T/pb145.txt")" = "$(awk '{for(i=1;i<=3;i++) printf "%s\t", $(145*3+i); printf "\n"}' "$T/bins.txt")" ]
then pass per_bin_files; else fail per_bin_files "files=$nfiles"; fi
# 8x8 floor grid looking up, irradiance pictures per modifier: .hdr and .exr hold the same pixels
awk 'BEGIN{for(y=7;y>=0;y--) for(x=0;x<8;x++) printf "%.4f %.4f 0.001 0 0 1\n", (x+.5)/8, (y+.5)/8}' > "$T/grid.txt"
check pictures_hdr rcontrib -I+ -ab -1 -ap "$T/a.pm" 60 -fac -x 8 -y 8 -o "$T/pic_%s.hdr" -M "$T/mods.txt" "$T/box.rad" < "$T/grid.txt"
check pictures_exr rcontrib -I+ -ab -1 -ap "$T/a.pm" 60 -fac -x 8 -y 8 -o "$T/pic_%s.exr" -M "$T/mods.txt" "$T/box.rad" < "$T/grid.txt"
ok=1
for s in solar1 solar2; do
    exr2hdr "$T/pic_$s.exr" "$T/conv_$s.hdr" 2>/dev/null || ok=0
    a=$(pvalue -h -H -d "$T/pic_$s.hdr" 2>/dev/null | md5sum); b=$(pvalue -h -H -d "$T/conv_$s.hdr" 2>/dev/null | md5sum)
    [ "$a" = "$b" ] || ok=0
    grep -aq "MODIFIER=$s" "$T/pic_$s.hdr" || ok=0
done
# the matrix output of the same rays holds the same values as the pictures (row 28 = pixel 28)
rcontrib -h- -I+ -ab -1 -ap "$T/a.pm" 60 -fa -m solar1 "$T/box.rad" < "$T/grid.txt" > "$T/grid.dc" 2>/dev/null
v=$(sed -n 29p "$T/grid.dc" | awk '{print $2}'); pv=$(pvalue -h -H -d "$T/pic_solar1.hdr" | sed -n 29p | awk '{print $2}')
if [ "$ok" = 1 ] && close "$pv" "$v" 0.01; then pass pictures_same; else fail pictures_same "ok=$ok pic=$pv mtx=$v"; fi
# one modifier: a single picture column (the spool's one-column layout) holds the matrix's values
check picture_one_column rcontrib -I+ -ab -1 -ap "$T/a.pm" 60 -fac -x 8 -y 8 -o "$T/one_%s.hdr" -m solar1 "$T/box.rad" < "$T/grid.txt"
r=$(paste <(pvalue -h -H -d "$T/one_solar1.hdr" 2>/dev/null) "$T/grid.dc" | awk 'NF == 6 {n++; d = $2 - $5; if (d < 0) d = -d;
    if (d > 0.01 * ($5 < 0 ? -$5 : $5) + 1e-12) bad++} END {print n + 0, bad + 0}')
if [ "$r" = "64 0" ]; then pass picture_one_column_values; else fail picture_one_column_values "pixels, mismatches: $r"; fi
check_fails pictures_need_one_bin "one value per stream" rcontrib -I+ -ab -1 -ap "$T/a.pm" 60 -fac -x 8 -y 8 \
    -e MF:1 -f reinhart.cal -b rbin -bn Nrbins -m solar1 -o "$T/x.hdr" "$T/box.rad" < "$T/grid.txt"
# -t progress reports on stderr
rcontrib -I+ -ab -1 -ap "$T/a.pm" 60 -t 1e-9 -fa -y 64 -M "$T/mods.txt" "$T/box.rad" < "$T/grid.txt" > /dev/null 2> "$T/prog.txt"
if grep -q "done" "$T/prog.txt"; then pass progress_reports; else fail progress_reports "$(head -2 "$T/prog.txt")"; fi
# bounded memory: 146 per-bin pictures from a cache of 1k photons (the map holds 40k) stay far
# below cache + 300 MB (pictures are spooled to disk, not held in memory)
if [ -x /usr/bin/time ]; then
    awk 'BEGIN{for(i=0;i<64*64;i++) printf "%.4f %.4f 0.001 0 0 1\n", (i%64+.5)/64, (int(i/64)+.5)/64}' > "$T/grid64.txt"
    mkdir -p "$T/rss"
    /usr/bin/time -f "%M" -o "$T/rss.txt" rcontrib -I+ -ab -1 -apd- -ap "$T/a.pm" 60 -aC 1k -fac -x 64 -y 64 \
        -e MF:1 -f reinhart.cal -b rbin -bn Nrbins -o "$T/rss/b%03d.hdr" -m solar1 "$T/box.rad" < "$T/grid64.txt" 2>/dev/null
    rss=$(tail -1 "$T/rss.txt"); n=$(ls "$T/rss" | wc -l)
    if [ "$n" = 146 ] && [ "${rss:-999999}" -lt 307200 ]; then pass bounded_rss; else fail bounded_rss "pictures=$n rss=${rss}kB"; fi
else skip bounded_rss "no /usr/bin/time"; fi
# coherent order: -fc pictures of known size gathered in batches of 0.05 MB (HELIODON_RC_BATCH_MB:
# ~ 25 batches) with a cache of 1k photons (16 pages of 64 photons: -apZ 64; the map holds 40k):
# every pixel equals the streamed path's record (-ff to standard output, input order),
# RGBE-encoded by pvalue -r: the decoded pixels compared bit for bit
mkdir -p "$T/coh"
mkpmap -apC "$T/z.pm" 40k -apZ 64 -apo port_m -apr 3 -n 2 "$T/box.rad" 2>/dev/null
awk 'BEGIN{for(i=0;i<64*64;i++) printf "%.4f %.4f 0.001 0 0 1\n", (i%64+.5)/64, (int(i/64)+.5)/64}' > "$T/grid64.txt"
HELIODON_RC_BATCH_MB=0.05 rcontrib -I+ -ab -1 -ap "$T/z.pm" 60 -aC 1k -stats -fac -x 64 -y 64 -o "$T/coh/%s.hdr" -M "$T/mods.txt" \
    "$T/box.rad" < "$T/grid64.txt" 2> "$T/coh.err"
ok=1
for s in solar1 solar2; do
    rcontrib -h -I+ -ab -1 -ap "$T/z.pm" 60 -aC 1k -faf -y 4096 -m $s "$T/box.rad" < "$T/grid64.txt" 2>/dev/null |
        pvalue -r -h -df -y 64 +x 64 -ff > "$T/coh/str_$s.hdr" 2>/dev/null || ok=0
    a=$(pvalue -h -H -df "$T/coh/$s.hdr" 2>/dev/null | md5sum); b=$(pvalue -h -H -df "$T/coh/str_$s.hdr" 2>/dev/null | md5sum)
    [ -s "$T/coh/$s.hdr" ] && [ "$a" = "$b" ] || ok=0
done
if [ "$ok" = 1 ] && grep -q "page reads" "$T/coh.err"; then pass coherent_same_as_streamed
else fail coherent_same_as_streamed "$(head -3 "$T/coh.err")"; fi
# the switch: binned lookups (146 Reinhart bins, each point searched alone) in the sunlit patch read pages of
# 64 photons; with a cache of 16 pages the first batch (0.5 MB: ~ 20 batches) overflows it, so the
# rest goes in batches of the budget in the order of the lookup points; with the default cache
# (the whole map decoded, nothing evicted) the run keeps the input order.  The 146 pictures of
# the two runs have identical pixels.
mkdir -p "$T/sw1" "$T/sw0"
awk 'BEGIN{for(i=0;i<64*64;i++) printf "%.4f %.4f 0.001 0 0 1\n", .26+.48*(i%64+.5)/64, .26+.48*(int(i/64)+.5)/64}' > "$T/gridsun.txt"
for c in 1k 4m; do
    d=$T/sw1; [ $c = 4m ] && d=$T/sw0
    HELIODON_RC_BATCH_MB=0.5 rcontrib -I+ -ab -1 -apd- -ap "$T/z.pm" 60 -aC $c -stats -fac -x 64 -y 64 -e MF:1 -f reinhart.cal \
        -b rbin -bn Nrbins -o "$d/b%03d.hdr" -m solar1 "$T/box.rad" < "$T/gridsun.txt" 2> "$d.err"
done
ok=1; n=0
for f in "$T"/sw1/b*.hdr; do
    a=$(pvalue -h -H -df "$f" 2>/dev/null | md5sum); b=$(pvalue -h -H -df "$T/sw0/$(basename "$f")" 2>/dev/null | md5sum)
    [ "$a" = "$b" ] || ok=0; n=$((n + 1))
done
if [ "$ok" = 1 ] && [ "$n" = 146 ] && grep -q "in the order of their lookup points" "$T/sw1.err" && ! grep -q overflowed "$T/sw0.err"
then pass coherent_after_overflow
else fail coherent_after_overflow "ok=$ok n=$n $(grep -h overflowed "$T"/sw?.err | head -2)"; fi
