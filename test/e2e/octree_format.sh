#!/bin/bash
# Octrees both ways: heliodon's oconv writes Radiance's octree format
# (unfrozen: file names; frozen -f: scene data), heliodon reads Radiance's
# octrees (the shared reference octrees, and the frozen form).  With
# RADIANCE_BIN set to Radiance's bin directory, Radiance's rtrace also
# renders heliodon's octrees (the recorded check is in docs/design/octree.md).
. test/e2e/lib.sh
B=$REF/scenes/box
if ! have_ref scenes/box; then skip octree "no reference folder $REF"; exit 0; fi
T=$(cd "$T" && pwd)
cd "$B" || exit 1
B=$PWD
FILES="box_room.rad box_window.rad sun_clear_0101_1030.rad"
RT="rtrace -h -I+ -ab 0 -dj 0 -dt 0 -dc 1 -st 0 -lr 12 -lw 1e-6"

# heliodon on the scene text, and on Radiance's own octree of it
$RT $FILES < sensors.pts > "$T/text.dat" 2>"$T/err" || fail rtrace_text "$(cat "$T/err")"
$RT box_sun.oct < sensors.pts > "$T/radoct.dat" 2>"$T/err" || fail rtrace_radiance_octree "$(cat "$T/err")"
nz=$(awk '$1>0' "$T/text.dat" | wc -l)
if [ "$nz" -ge 5 ] && cmp -s "$T/text.dat" "$T/radoct.dat"; then pass reads_radiance_octree
else fail reads_radiance_octree "$nz lit sensors; $(diff "$T/text.dat" "$T/radoct.dat" | head -2 | tr '\n' ' ')"; fi

# heliodon's oconv: Radiance's header, magic, cube and file list
oconv $FILES > "$T/h.oct" 2>"$T/err" || fail oconv "$(cat "$T/err")"
# the NUL-ended strings after the header and the 2-byte magic number
hbytes() { head -n "$(awk '/^$/{print NR; exit}' "$1")" "$1" | wc -c; }
strs() { tail -c +$(($(hbytes "$1") + 3)) "$1" | tr '\0' '\n' | head -n "$2"; }
magic=$(tail -c +$(($(hbytes "$T/h.oct") + 1)) "$T/h.oct" | od -An -N2 -tu1 | tr -s ' ')
if [ "$(sed -n 3p "$T/h.oct")" = "FORMAT=Radiance_octree" ] && [ "$magic" = " 1 31" ]; then pass octree_header
else fail octree_header "format '$(sed -n 3p "$T/h.oct")' magic '$magic'"; fi
if [ "$(strs "$T/h.oct" 8)" = "$(strs box_sun.oct 8)" ]; then pass octree_cube_and_files
else fail octree_cube_and_files "$(strs "$T/h.oct" 8 | tr '\n' ' ') vs $(strs box_sun.oct 8 | tr '\n' ' ')"; fi
$RT "$T/h.oct" < sensors.pts > "$T/hoct.dat" 2>"$T/err"
cmp -s "$T/hoct.dat" "$T/text.dat" && pass reads_own_octree || fail reads_own_octree "$(cat "$T/err")"

# frozen: without heliodon's cache (cut at the trailer's offset) the file is
# a plain frozen Radiance octree, read from its scene data
oconv -f $FILES > "$T/hf.oct" 2>"$T/err" || fail oconv_f "$(cat "$T/err")"
off=$(tail -c 8 "$T/hf.oct" | od -An -tu1 | awk '{v=0; for(i=NF;i>=1;i--) v=v*256+$i; print v}')
[ "$(tail -c 16 "$T/hf.oct" | head -c 8)" = HDSCACHE ] || fail frozen_trailer "no HDSCACHE trailer"
head -c "$off" "$T/hf.oct" > "$T/frozen.oct"
if [ -z "$(strs "$T/frozen.oct" 5 | sed -n 5p)" ]; then pass frozen_lists_no_files
else fail frozen_lists_no_files "$(strs "$T/frozen.oct" 5 | tr '\n' ' ')"; fi
(cd "$T" && $RT frozen.oct < "$B/sensors.pts" > frozen.dat 2>err) || fail rtrace_frozen "$(cat "$T/err")"
m=$(paste "$T/frozen.dat" "$T/text.dat" | awk '{for(i=1;i<=3;i++){d=$i-$(i+3); if(d<0)d=-d; r=$(i+3)>0?d/$(i+3):d; if(r>m)m=r}} END{print m+0}')
n=$(wc -l < "$T/frozen.dat")
if [ "$n" -eq 28 ] && le "$m" 1e-6; then pass reads_frozen_octree; else fail reads_frozen_octree "$n lines, max rel $m"; fi

# damaged octrees are refused with the byte offset
head -c $((off - 40)) "$T/frozen.oct" > "$T/trunc.oct"
check_fails truncated_frozen "trunc.oct.*(byte offset|unexpected end)" rtrace -h "$T/trunc.oct"
printf '#?RADIANCE\nFORMAT=Radiance_octree\n\n\001\077junk' > "$T/bad.oct"
check_fails bad_magic "bad.oct.*magic" rtrace -h "$T/bad.oct"

# Radiance's rtrace on heliodon's octrees (only when Radiance is given)
if [ -n "${RADIANCE_BIN:-}" ] && [ -x "$RADIANCE_BIN/rtrace" ]; then
    export RAYPATH=".:${RADIANCE_LIB:-$RADIANCE_BIN/../lib}"
    RRT="$RADIANCE_BIN/rtrace -h -I+ -ab 0 -dj 0 -dt 0 -dc 1 -st 0 -lr 12 -lw 1e-6"
    $RRT box_sun.oct < sensors.pts > "$T/r_ref.dat" 2>/dev/null
    $RRT "$T/h.oct" < sensors.pts > "$T/r_h.dat" 2>"$T/err"
    $RRT "$T/hf.oct" < sensors.pts > "$T/r_hf.dat" 2>>"$T/err"
    if [ -s "$T/r_ref.dat" ] && cmp -s "$T/r_ref.dat" "$T/r_h.dat" && cmp -s "$T/r_ref.dat" "$T/r_hf.dat"; then
        pass radiance_reads_heliodon_octree
    else fail radiance_reads_heliodon_octree "$(head -2 "$T/err" | tr '\n' ' ')"; fi
else
    skip radiance_reads_heliodon_octree "RADIANCE_BIN not set (checked beside the project: docs/design/octree.md)"
fi
