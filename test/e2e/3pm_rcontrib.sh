#!/bin/bash
# rcontrib / rfluxmtx end to end: output layouts and headers as Radiance
# writes them, -o streams (%s, %d), pictures from vwrays rays, -c, and
# bad inputs.  Values are checked in test/unit/test_contrib.c.
. test/e2e/lib.sh
BOX=$REF/scenes/box
if ! have_ref scenes/box; then skip all "no ../shared/ref/scenes/box"; exit 0; fi

# ---- V-style run: header layout (compare with a3_V_sensors.vmx) ----
rcontrib -ab 2 -ad 64 -lw 1e-4 -I+ -y 28 -faf -f klems_full.cal -p RHS=+1 -bn Nkbins -b 'kbin(0,1,0,0,0,1)' \
    -m window_rx "$BOX/box_room.rad" "$BOX/window_rx_pts.rad" < "$BOX/sensors.pts" > "$T/v.vmx" 2> "$T/v.err"
check v_runs test -s "$T/v.vmx"
getinfo "$T/v.vmx" | sed 's/^[[:space:]]*//' > "$T/v.info"
ok=1
for l in 'NCOMP=3' 'NROWS=28' 'NCOLS=145' 'BigEndian=0' 'FORMAT=float'; do grep -q "^$l" "$T/v.info" || ok=0; done
# the same variables in the same order as Radiance's file
grep -E '^(NCOMP|NROWS|NCOLS|BigEndian|FORMAT)=' "$T/v.info" | cut -d= -f1 > "$T/v.vars"
getinfo "$BOX/a3_V_sensors.vmx" | sed 's/^[[:space:]]*//' | grep -E '^(NCOMP|NROWS|NCOLS|BigEndian|FORMAT)=' | cut -d= -f1 > "$T/ref.vars"
cmp -s "$T/v.vars" "$T/ref.vars" || ok=0
grep -q '^SOFTWARE= heliodon' "$T/v.info" || ok=0
if [ $ok = 1 ]; then pass v_header; else fail v_header "$(tr '\n' ' ' < "$T/v.info")"; fi
# data starts 4-byte aligned and holds 28*145*3 floats
hb=$(( $(stat -c %s "$T/v.vmx") - 28 * 145 * 3 * 4 ))
if [ $hb -gt 0 ] && [ $((hb % 4)) = 0 ]; then pass v_size_aligned; else fail v_size_aligned "header bytes $hb"; fi
check v_rmtxop_reads bash -c "rmtxop -fa '$T/v.vmx' | grep -q 'NCOLS=145'"

# ---- ascii layout as rcontrib: one record per line, %.6e<TAB> per component ----
rcontrib -ab 1 -ad 16 -I+ -y 28 -fa -o "$T/a.dat" -f klems_full.cal -bn Nkbins -b 'kbin(0,1,0,0,0,1)' \
    -m window_rx "$BOX/box_room.rad" "$BOX/window_rx_pts.rad" < "$BOX/sensors.pts"
n=$(data_values "$T/a.dat" | wc -l)
lines=$(awk 'h {print} /^$/ {h=1}' "$T/a.dat" | wc -l)
fmtok=$(awk -F'\t' 'h { if (NF != 436 || $436 != "") bad=1; for (i = 1; i < NF; i++) if ($i !~ /^-?[0-9]\.[0-9][0-9][0-9][0-9][0-9][0-9]e[-+][0-9][0-9]$/) bad=1 } /^$/ {h=1} END {print bad ? 0 : 1}' "$T/a.dat")
if [ "$n" = $((28 * 435)) ] && [ "$lines" = 28 ] && [ "$fmtok" = 1 ]; then pass ascii_layout
else fail ascii_layout "values $n lines $lines fmt $fmtok"; fi

# ---- -o %s: one stream per modifier with MODIFIER=; -V+ ----
rcontrib -ab 1 -ad 32 -y 28 -I+ -fa -o "$T/m_%s.dat" -bn 1 -b 0 -m ground_glow \
    -f reinhartb.cal -p MF=1 -bn Nrbins -b rbin -m sky_glow "$BOX/box_room.rad" "$BOX/sky_rx.rad" < "$BOX/sensors.pts" 2>/dev/null
if grep -q '^MODIFIER=ground_glow' "$T/m_ground_glow.dat" && grep -q '^NCOLS=1$' "$T/m_ground_glow.dat" \
   && grep -q '^MODIFIER=sky_glow' "$T/m_sky_glow.dat" && grep -q '^NCOLS=145$' "$T/m_sky_glow.dat"; then
    pass o_modifier_streams; else fail o_modifier_streams "$(ls "$T")"; fi
# existing output without -fo is refused, with -fo overwritten
check_fails o_exists 'exists' rcontrib -ab 0 -y 28 -I+ -o "$T/m_%s.dat" -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts"
check o_force rcontrib -fo -ab 0 -y 28 -I+ -o "$T/m_%s.dat" -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts"

# ---- -c 0: one record, the sum of all rays ----
rcontrib -c 0 -ab 1 -ad 64 -I+ -fa -bn 1 -b 0 -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts" > "$T/c0.dat" 2>/dev/null
nv=$(data_values "$T/c0.dat" | wc -l)
# 28 points: 25 floor points see the whole sky (pi each), 3 wall points half of it (pi/2): 25 pi + 1.5 pi
v=$(data_values "$T/c0.dat" | head -1)
if [ "$nv" = 3 ] && close "$v" "$(awk 'BEGIN{print 26.5*3.14159265}')" 0.02; then pass c0_sum; else fail c0_sum "$nv values, first $v"; fi

# ---- pictures from vwrays rays: one per bin (%d), resolution string ----
mkdir -p "$T/img"
sed "s|o=a3_vimg/v%03d.hdr|o=$T/img/v%03d.hdr|" "$BOX/window_rx_img.rad" > "$T/rx_img.rad"
vwrays -ff -x 16 -y 16 -vf "$BOX/fish.vf" | rfluxmtx -ffc -x 16 -y 16 -ld- -ab 1 -ad 16 -lw 1e-3 - "$T/rx_img.rad" "$BOX/box_room.rad"
nimg=$(ls "$T/img" | wc -l)
getinfo "$T/img/v007.hdr" 2>&1 | sed 's/^[[:space:]]*//' > "$T/img.info"
if [ "$nimg" = 145 ] && grep -q '^MODIFIER=window_rx' "$T/img.info" && grep -q '^BIN=7$' "$T/img.info" \
   && grep -q '^NROWS=256$' "$T/img.info" && grep -q '^FORMAT=32-bit_rle_rgbe' "$T/img.info"; then
    pass picture_streams; else fail picture_streams "$nimg files; $(tr '\n' ' ' < "$T/img.info")"; fi
check picture_readable bash -c "getinfo -d '$T/img/v007.hdr' | grep -Eq -- '-Y +16 \+X +16' && pvalue -h -H -d '$T/img/v007.hdr' | wc -l | grep -q '^256$'"
# same layout as Radiance's picture of that bin
getinfo "$BOX/a3_vimg/v007.hdr.gz" 2>/dev/null | sed 's/^[[:space:]]*//' | grep -E '^(NCOMP|MODIFIER|BIN|NROWS|FORMAT)=' | cut -d= -f1 > "$T/refimg.vars"
grep -E '^(NCOMP|MODIFIER|BIN|NROWS|FORMAT)=' "$T/img.info" | cut -d= -f1 > "$T/img.vars"
if [ -s "$T/refimg.vars" ]; then
    if cmp -s "$T/img.vars" "$T/refimg.vars"; then pass picture_header_as_radiance; else fail picture_header_as_radiance "$(tr '\n' ' ' < "$T/img.vars")"; fi
else skip picture_header_as_radiance "cannot read the gzipped reference picture"; fi

# ---- rfluxmtx with a sender: D-style matrix 145 x 146 ----
rfluxmtx -ff -c 4 -ab 1 -ad 16 -lw 1e-3 "$BOX/window_tx.rad" "$BOX/sky_rx.rad" "$BOX/box_room.rad" > "$T/d.dmx"
getinfo "$T/d.dmx" | sed 's/^[[:space:]]*//' > "$T/d.info"
if grep -q '^NROWS=145$' "$T/d.info" && grep -q '^NCOLS=146$' "$T/d.info" && grep -q '^rfluxmtx ' "$T/d.info"; then
    pass rfluxmtx_sender_dims; else fail rfluxmtx_sender_dims "$(tr '\n' ' ' < "$T/d.info")"; fi
check rfluxmtx_verbose bash -c "rfluxmtx -v -c 1 -ab 0 '$BOX/window_tx.rad' '$BOX/sky_rx.rad' '$BOX/box_room.rad' 2>&1 >/dev/null | grep -q 'reinhartb.cal -p MF=1,rNx=0,rNy=0,rNz=-1,Ux=0,Uy=1,Uz=0,RHS=+1 -bn Nrbins -b rbin -m sky_glow'"

# ---- bad inputs ----
check_fails unknown_modifier "unknown modifier 'nosuch'" rcontrib -ab 0 -m nosuch "$BOX/sky_rx.rad" < "$BOX/sensors.pts"
check_fails bad_bin_expr "'\\)' expected" rcontrib -b 'floor(Dx*4' -bn 4 -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts"
check_fails undefined_bin 'nobin: undefined variable' rcontrib -ab 0 -b nobin -bn 4 -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts"
check_fails bad_cal_file "cannot find file 'mybins.cal'" rcontrib -f mybins.cal -b bin -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts"
check_fails nonzero_const 'illegal non-zero constant for bin \(3\)' rcontrib -b 3 -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts"
check_fails xy_mismatch 'more input rays than -x 4 -y 4' rcontrib -ab 0 -x 4 -y 4 -I+ -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts"
head -c 100 /dev/zero > "$T/trunc.bin"
check_fails truncated_rays 'truncated' rcontrib -ab 0 -ff -m sky_glow "$BOX/sky_rx.rad" < "$T/trunc.bin"
printf '1 2 3 0 0\n' > "$T/short.txt"
check_fails incomplete_ray 'incomplete' rcontrib -ab 0 -m sky_glow "$BOX/sky_rx.rad" < "$T/short.txt"
grep -v '^#' "$BOX/window_rx_pts.rad" > "$T/nocomment.rad"
check_fails no_rfluxmtx_comment 'no #@rfluxmtx' rfluxmtx -I+ -y 28 - "$T/nocomment.rad" "$BOX/box_room.rad" < "$BOX/sensors.pts"
check_fails controlled_option 'controlled by rfluxmtx' rfluxmtx -m window_rx - "$BOX/window_rx_pts.rad" "$BOX/box_room.rad" < "$BOX/sensors.pts"
check_fails sender_no_I 'pass-through' rfluxmtx -I+ "$BOX/window_tx.rad" "$BOX/sky_rx.rad" "$BOX/box_room.rad"
printf '#@rfluxmtx h=zz u=Z\nvoid glow g 0 0 4 1 1 1 0\ng polygon p 0 0 9 0 0 0 1 0 0 0 1 0\n' > "$T/badh.rad"
check_fails bad_basis 'unknown basis' rfluxmtx -I+ -y 1 - "$T/badh.rad" "$BOX/box_room.rad" < /dev/null
check_fails photon_map_missing 'x.pm: cannot open' rcontrib -ap "$T/x.pm" 10 -m sky_glow "$BOX/sky_rx.rad" < /dev/null
check_fails fc_needs_xy 'needs -x and -y' rcontrib -ffc -m sky_glow "$BOX/sky_rx.rad" < /dev/null

# ---- -M file, light sources by shadow rays through glass: Radiance's direct-sun DCs ----
# (a4_dc/sens_mf1_direct_ab0.dc: rcontrib -I+ -ab 0 -dj 0 ... -M mods_mf1.txt box_suns_mf1.oct; deterministic)
if [ -f "$BOX/box_suns_mf1.oct" ] && [ -f "$BOX/a4_dc/sens_mf1_direct_ab0.dc" ]; then
    (cd "$BOX" && rcontrib -I+ -ab 0 -dj 0 -st 0 -lr 12 -fa -y 28 -M mods_mf1.txt box_suns_mf1.oct < sensors.pts) > "$T/sun.dc" 2> "$T/sun.err"
    m=$(maxrel "$T/sun.dc" "$BOX/a4_dc/sens_mf1_direct_ab0.dc" 1e-12)
    if [ $? = 0 ] && le "$m" 2e-6; then pass direct_sun_dc_vs_radiance; else fail direct_sun_dc_vs_radiance "max rel $m $(head -2 "$T/sun.err")"; fi
    # same layout: identical apart from the last digit of some values
    a=$(awk 'h {print NF} /^$/ {h=1}' "$T/sun.dc" | sort -u | tr '\n' ' ')
    b=$(awk 'h {print NF} /^$/ {h=1}' "$BOX/a4_dc/sens_mf1_direct_ab0.dc" | sort -u | tr '\n' ' ')
    if [ "$a" = "$b" ]; then pass direct_sun_layout; else fail direct_sun_layout "$a vs $b"; fi
else
    skip direct_sun_dc_vs_radiance "no A4 reference"
fi

# ---- -h- (no header), -fd (double, 8-byte aligned), -c N averaging ----
rcontrib -h- -ab 0 -y 28 -I+ -fa -bn 1 -b 0 -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts" > "$T/nohdr.dat" 2>/dev/null
if head -c 2 "$T/nohdr.dat" | grep -q '^[0-9]' && [ "$(wc -l < "$T/nohdr.dat")" = 28 ]; then pass no_header; else fail no_header "$(head -c 40 "$T/nohdr.dat")"; fi
rcontrib -ab 1 -ad 16 -y 28 -I+ -fad -bn 1 -b 0 -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts" > "$T/d.dat" 2>/dev/null
hb=$(( $(stat -c %s "$T/d.dat") - 28 * 3 * 8 ))
if [ $hb -gt 0 ] && [ $((hb % 8)) = 0 ] && grep -aq '^FORMAT=double' "$T/d.dat"; then pass double_aligned; else fail double_aligned "header $hb bytes"; fi
# -c 4 over 28 points: 7 records, each the mean of 4 rays (4 floor points each see the sky: pi)
rcontrib -c 4 -ab 1 -ad 64 -y 7 -I+ -fa -bn 1 -b 0 -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts" > "$T/c4.dat" 2>/dev/null
first=$(data_values "$T/c4.dat" | head -1); nrec=$(awk 'h {n++} /^$/ {h=1} END {print n}' "$T/c4.dat")
if [ "$nrec" = 7 ] && close "$first" 3.14159265 1e-6; then pass c_average; else fail c_average "$nrec records, first $first"; fi
check_fails c_partial 'not a multiple of -c 5' rcontrib -c 5 -ab 0 -I+ -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts"

# ---- -o '!command': one pipe per stream ----
rcontrib -ab 0 -y 28 -I+ -fa -o "!cat > $T/pipe_%s.dat" -bn 1 -b 0 -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts" 2>/dev/null
if grep -q '^MODIFIER=sky_glow' "$T/pipe_sky_glow.dat" 2>/dev/null && [ "$(data_values "$T/pipe_sky_glow.dat" | wc -l)" = 84 ]; then
    pass o_command; else fail o_command "$(ls "$T" | grep pipe)"; fi
check_fails o_command_fails 'command failed|write error|Broken pipe' rcontrib -ab 0 -y 28 -I+ -o '!exit 3' -m sky_glow "$BOX/sky_rx.rad" < "$BOX/sensors.pts"

# ---- determinism: same output with 1 and 2 threads (sender and pass-through modes) ----
rfluxmtx -h- -n 1 -ff -c 2 -ab 2 -ad 16 -lw 1e-4 "$BOX/window_tx.rad" "$BOX/sky_rx.rad" "$BOX/box_room.rad" > "$T/n1.bin"
rfluxmtx -h- -n 2 -ff -c 2 -ab 2 -ad 16 -lw 1e-4 "$BOX/window_tx.rad" "$BOX/sky_rx.rad" "$BOX/box_room.rad" > "$T/n2.bin"
if cmp -s "$T/n1.bin" "$T/n2.bin" && [ "$(stat -c %s "$T/n1.bin")" = $((145 * 146 * 12)) ]; then pass threads_sender; else fail threads_sender; fi
rfluxmtx -h- -n 1 -I+ -faf -ab 3 -ad 64 - "$BOX/window_rx_pts.rad" "$BOX/box_room.rad" < "$BOX/sensors.pts" > "$T/p1.bin"
rfluxmtx -h- -n 2 -I+ -faf -ab 3 -ad 64 - "$BOX/window_rx_pts.rad" "$BOX/box_room.rad" < "$BOX/sensors.pts" > "$T/p2.bin"
if cmp -s "$T/p1.bin" "$T/p2.bin"; then pass threads_passthrough; else fail threads_passthrough; fi
