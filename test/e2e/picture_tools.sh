# End-to-end tests of getinfo and pvalue against Radiance reference files.
. test/e2e/lib.sh

BOX=$REF/scenes/box
OFFICE=$REF/scenes/office

# --- synthetic picture (no reference needed): 40 x 30 ramp, written by pvalue -r
awk 'BEGIN { for (y = 0; y < 30; y++) for (x = 0; x < 40; x++)
        printf "%g %g %g\n", x / 40, (y + 1) * 10, (x == y) ? 0 : 0.001 * (x + 1) }' > "$T/ramp.txt"
if pvalue -r -h -H -d -y 30 +x 40 "$T/ramp.txt" > "$T/ramp.hdr" 2> "$T/err"; then
    pass synth_reverse_ascii
else
    fail synth_reverse_ascii "$(cat "$T/err")"
fi
# the header carries the command and the picture format; the resolution follows
if getinfo < "$T/ramp.hdr" | grep -q '^pvalue -r -h -H -d -y 30 +x 40$' &&
   [ "$(getinfo -d < "$T/ramp.hdr")" = "-Y       30 +X       40" ]; then
    pass synth_header
else
    fail synth_header "$(getinfo < "$T/ramp.hdr" | tr '\n' '|')"
fi
# values come back within RGBE precision (1/128 relative of the largest channel)
pvalue -h -H -d "$T/ramp.hdr" > "$T/ramp.back"
if paste "$T/ramp.txt" "$T/ramp.back" | awk '{ m = $1; if ($2 > m) m = $2; if ($3 > m) m = $3
        for (i = 1; i <= 3; i++) { d = $i - $(i+3); if (d < 0) d = -d; if (d > m / 128 + 1e-30) bad++ } }
        END { exit bad > 0 || NR != 1200 }'; then
    pass synth_values
else
    fail synth_values "values differ beyond RGBE precision"
fi
# positions: x from the left, y from the bottom, first scanline at the top
first=$(pvalue -h -H "$T/ramp.hdr" | head -1 | awk '{print $1, $2}')
last=$(pvalue -h -H "$T/ramp.hdr" | tail -1 | awk '{print $1, $2}')
if [ "$first" = "0 29" ] && [ "$last" = "39 0" ]; then pass positions; else fail positions "first $first last $last"; fi

# --- getinfo against Radiance's own output
if have_ref scenes/box; then
    for f in "$BOX"/a2_*.hdr; do
        b=$(basename "$f" .hdr)
        [ -f "$BOX/$b.getinfo.txt" ] || continue
        (cd "$BOX" && getinfo "$b.hdr" && getinfo -d "$b.hdr") > "$T/$b.gi"
        if cmp -s "$T/$b.gi" "$BOX/$b.getinfo.txt"; then pass "getinfo_ref_$b"
        else fail "getinfo_ref_$b" "$(diff "$T/$b.gi" "$BOX/$b.getinfo.txt" | head -5 | tr '\n' '|')"; fi
    done
    f=$BOX/a2_clear_persp.hdr
    # stdin form prints the header exactly as stored (plus the empty line)
    getinfo < "$f" > "$T/hdr.txt"
    hl=$(wc -c < "$T/hdr.txt")
    if head -c "$hl" "$f" | cmp -s - "$T/hdr.txt"; then pass getinfo_stdin_header; else fail getinfo_stdin_header; fi
    # "getinfo -" strips the header, "getinfo -d -" the resolution string too
    tail -c +$((hl + 1)) "$f" > "$T/body"
    if getinfo - < "$f" | cmp -s - "$T/body"; then pass getinfo_strip; else fail getinfo_strip; fi
    tail -c +$((hl + 25)) "$f" > "$T/body2"
    if getinfo -d - < "$f" | cmp -s - "$T/body2"; then pass getinfo_strip_resolution; else fail getinfo_strip_resolution; fi
    # +d: header then the dimensions
    if [ "$(cd "$BOX" && getinfo +d a2_clear_persp.hdr | tail -1)" = "	-Y      256 +X      256" ]; then
        pass getinfo_plus_d; else fail getinfo_plus_d; fi
    # -a adds lines before FORMAT, -r removes them again: the original file comes back
    getinfo -a "EXPOSURE=2" "HD_TEST= a b" < "$f" > "$T/exp.hdr"
    if getinfo < "$T/exp.hdr" | tail -4 | head -3 | tr '\n' '|' | grep -q '^EXPOSURE=2|HD_TEST= a b|FORMAT=32-bit_rle_rgbe|$' &&
       getinfo -r EXPOSURE HD_TEST < "$T/exp.hdr" | cmp -s - "$f"; then
        pass getinfo_add_remove
    else
        fail getinfo_add_remove "$(getinfo < "$T/exp.hdr" | tail -5 | tr '\n' '|')"
    fi
    # -r with a full line replaces
    n=$(getinfo -r "EXPOSURE=16" < "$T/exp.hdr" | getinfo | grep -c '^EXPOSURE=')
    v=$(getinfo -r "EXPOSURE=16" < "$T/exp.hdr" | getinfo | grep '^EXPOSURE=')
    if [ "$n" = 1 ] && [ "$v" = "EXPOSURE=16" ]; then pass getinfo_replace; else fail getinfo_replace "$n $v"; fi
    # -c runs a command on the data, passing the header on with the command added
    getinfo -c cat < "$f" > "$T/c.hdr"
    if getinfo < "$T/c.hdr" | grep -q '^cat$' && getinfo - < "$T/c.hdr" | cmp -s - "$T/body"; then
        pass getinfo_command; else fail getinfo_command; fi
    # octree bounding cube (the four strings stored after the octree magic)
    if [ "$(cd "$BOX" && getinfo -d box_clear.oct)" = "box_clear.oct: -100.00001 -100.00001 -98.50051 200.00002" ]; then
        pass getinfo_octree; else fail getinfo_octree "$(cd "$BOX" && getinfo -d box_clear.oct)"; fi
    # gzip-compressed pictures are read transparently
    if [ "$(getinfo -d < "$BOX/a3_vimg/v000.hdr.gz")" = "-Y      128 +X      128" ]; then
        pass getinfo_gzip; else fail getinfo_gzip "$(getinfo -d < "$BOX/a3_vimg/v000.hdr.gz")"; fi
else
    skip getinfo_ref "no reference folder $BOX"
fi
if have_ref scenes/office; then
    ok=1
    for f in "$OFFICE"/*.hdr; do
        want=$(head -c 4096 "$f" | grep -a -m1 -E '^[-+][XY] +[0-9]+ [-+][XY] +[0-9]+$')
        got=$(getinfo -d "$f")
        [ "$got" = "$f: $want" ] || { ok=0; echo "  $got <> $want"; }
    done
    [ $ok = 1 ] && pass getinfo_d_office || fail getinfo_d_office
fi

# --- pvalue round trips on reference pictures
if have_ref scenes/box; then
    f=$BOX/a2_clear_fish.hdr
    # float, standard order: the data section comes back byte for byte
    pvalue -h -H -df "$f" | pvalue -r -h -H -df -y 256 +x 256 > "$T/rt.hdr"
    if getinfo - < "$T/rt.hdr" | cmp -s - <(getinfo - < "$f"); then pass pvalue_roundtrip_float
    else fail pvalue_roundtrip_float; fi
    # ascii with positions, header and resolution string taken from the input
    pvalue "$f" | pvalue -r > "$T/rt2.hdr"
    if getinfo - < "$T/rt2.hdr" | cmp -s - <(getinfo - < "$f") &&
       getinfo < "$T/rt2.hdr" | grep -q '^VIEW= -vta'; then pass pvalue_roundtrip_ascii
    else fail pvalue_roundtrip_ascii; fi
    # double, with a header on the data (FORMAT=double checked on input)
    pvalue -H -dd "$f" | pvalue -r -dd -y 256 +x 256 > "$T/rt3.hdr"
    if getinfo - < "$T/rt3.hdr" | cmp -s - <(getinfo - < "$f"); then pass pvalue_roundtrip_double
    else fail pvalue_roundtrip_double; fi
    # "-x 256 -y 256": Radiance's sign convention makes an X-major picture with both
    # axes decreasing; the file order of the values is unchanged
    pvalue -h -H -df "$f" | pvalue -r -h -H -df -x 256 -y 256 > "$T/rt4.hdr"
    if [ "$(getinfo -d < "$T/rt4.hdr")" = "-X      256 -Y      256" ] &&
       pvalue -h -H -df "$T/rt4.hdr" | cmp -s - <(pvalue -h -H -df "$f"); then pass pvalue_xy_order
    else fail pvalue_xy_order "$(getinfo -d < "$T/rt4.hdr")"; fi
    # bytes survive a byte round trip exactly
    pvalue -h -H -db "$f" > "$T/b1"
    pvalue -r -h -H -db -y 256 +x 256 < "$T/b1" | pvalue -h -H -db > "$T/b2"
    if [ "$(wc -c < "$T/b1")" = 196608 ] && cmp -s "$T/b1" "$T/b2"; then pass pvalue_roundtrip_byte
    else fail pvalue_roundtrip_byte; fi
    # -b: brightness = 0.265 R + 0.670 G + 0.065 B
    pvalue -h -H -d "$f" | head -2000 > "$T/rgb"
    pvalue -h -H -d -b "$f" | head -2000 > "$T/lum"
    if paste "$T/rgb" "$T/lum" | awk '{ l = 0.265074126*$1 + 0.670114631*$2 + 0.064811243*$3
            d = l - $4; if (d < 0) d = -d; if (d > 1e-3 * l + 1e-9) bad++ } END { exit bad > 0 || NR != 2000 }'; then
        pass pvalue_brightness; else fail pvalue_brightness; fi
    # -o undoes EXPOSURE, -e applies one (and +1 stops = x2)
    getinfo -a "EXPOSURE=4" < "$f" > "$T/e4.hdr"
    pvalue -h -H -d -o "$T/e4.hdr" | head -500 > "$T/o"
    pvalue -h -H -d -e 0.25 "$f" | head -500 > "$T/e"
    pvalue -h -H -d -e +1 "$f" | head -500 > "$T/e2"
    pvalue -h -H -d "$f" | head -500 > "$T/plain"
    if cmp -s "$T/o" "$T/e" &&
       paste "$T/plain" "$T/e2" | awk '{ for (i = 1; i <= 3; i++) { d = 2*$i - $(i+3); if (d < 0) d = -d; if (d > 1e-3 * $(i+3) + 1e-12) bad++ } } END { exit bad > 0 }'; then
        pass pvalue_exposure; else fail pvalue_exposure; fi
    if pvalue -h -e 2 "$f" > /dev/null && pvalue -e 2 "$f" | getinfo | grep -q '^EXPOSURE=2.000000e+00$'; then
        pass pvalue_exposure_header; else fail pvalue_exposure_header; fi
    # -u skips repeated pixels
    nu=$(pvalue -h -H -u "$f" | wc -l)
    if [ "$nu" -gt 1000 ] && [ "$nu" -lt 65536 ]; then pass pvalue_unique; else fail pvalue_unique "$nu"; fi
    # -df with -H writes NROWS/NCOLS/NCOMP and BigEndian for the matrix tools
    if pvalue -H -df "$f" | getinfo | tr '\n' '|' | grep -q 'NCOMP=3|NCOLS=256|NROWS=256|BigEndian=0|FORMAT=float'; then
        pass pvalue_matrix_header; else fail pvalue_matrix_header; fi
    # gzip input
    if [ "$(pvalue -h -H -d "$BOX/a3_vimg/v000.hdr.gz" | wc -l)" = 16384 ]; then pass pvalue_gzip; else fail pvalue_gzip; fi
fi

# --- less common pvalue options
if have_ref scenes/box; then
    f=$BOX/a2_overcast_persp.hdr
    pvalue -h -H -d "$f" > "$T/rgb.all"
    # -R: blue green red; -pG: green only
    if pvalue -h -H -d -R "$f" | cmp -s - <(awk '{printf "%15s %15s %15s\n", $3, $2, $1}' "$T/rgb.all") &&
       pvalue -h -H -d -pG "$f" | cmp -s - <(awk '{printf "%15s\n", $2}' "$T/rgb.all"); then
        pass pvalue_order_primary; else fail pvalue_order_primary; fi
    # -n: all red, then green, then blue; reverse -n restores the picture
    pvalue -h -H -n -df "$f" > "$T/n.f"
    pvalue -h -H -pR -df "$f" > "$T/r.f"; pvalue -h -H -pG -df "$f" > "$T/g.f"; pvalue -h -H -pB -df "$f" > "$T/b.f"
    if cat "$T/r.f" "$T/g.f" "$T/b.f" | cmp -s - "$T/n.f" &&
       pvalue -r -h -H -n -df -y 256 +x 256 "$T/n.f" | getinfo - | cmp -s - <(getinfo - < "$f"); then
        pass pvalue_noninterleaved; else fail pvalue_noninterleaved; fi
    # three separate channel files
    if pvalue -r -h -H -df -y 256 +x 256 "$T/r.f" "$T/g.f" "$T/b.f" | getinfo - | cmp -s - <(getinfo - < "$f"); then
        pass pvalue_three_files; else fail pvalue_three_files; fi
    # -di: integers, value * 256 truncated
    if pvalue -h -H -di "$f" | head -300 | cmp -s - <(head -300 "$T/rgb.all" |
            awk '{printf "%d %d %d\n", int($1*256), int($2*256), int($3*256)}'); then
        pass pvalue_integers; else fail pvalue_integers "(%.3e rounding can differ at integer boundaries)"; fi
    # 16-bit words come back within RGBE precision (8-bit mantissas); -dW is byte-swapped
    pvalue -h -H -dw "$f" > "$T/w1"
    pvalue -r -h -H -dw -y 256 +x 256 "$T/w1" | pvalue -h -H -dw > "$T/w2"
    pvalue -h -H -dW "$f" > "$T/w3"
    if paste <(od -An -v -tu2 -w6 "$T/w1") <(od -An -v -tu2 -w6 "$T/w2") | awk '
            { m = $1; if ($2 > m) m = $2; if ($3 > m) m = $3
              for (i = 1; i <= 3; i++) { d = $i - $(i+3); if (d < 0) d = -d; if (d > m / 128 + 1) bad++ } }
            END { exit bad > 0 || NR != 65536 }' &&
       [ "$(od -An -tx1 -N2 "$T/w1" | tr -d ' ')" = "$(od -An -tx1 -j1 -N1 "$T/w3" | tr -d ' ')$(od -An -tx1 -N1 "$T/w3" | tr -d ' ')" ]; then
        pass pvalue_words; else fail pvalue_words; fi
    # -g 2: forward takes square roots, reverse squares them back
    a=$(pvalue -h -H -d "$f" | sed -n 1000p | awk '{print $2}')
    b=$(pvalue -h -H -d -g 2 "$f" | sed -n 1000p | awk '{print $2 * $2}')
    if close "$b" "$a" 0.01; then pass pvalue_gamma; else fail pvalue_gamma "$a vs $b"; fi
    # -s skips a foreign prefix
    { printf 'JUNK!'; cat "$f"; } > "$T/junk.hdr"
    if pvalue -s 5 -h -H -d "$T/junk.hdr" | cmp -s - "$T/rgb.all"; then pass pvalue_skip; else fail pvalue_skip; fi
    # -u on reverse writes flat scanlines: data = 4 bytes a pixel
    n=$(pvalue -h -H -df "$f" | pvalue -r -u -h -H -df -y 256 +x 256 | getinfo -d - | wc -c)
    if [ "$n" = 262144 ]; then pass pvalue_reverse_flat; else fail pvalue_reverse_flat "$n bytes"; fi
    # -pXYZ writes an XYZE picture; -b on it is Y, -O converts Y to W/sr/m2
    pvalue -h -H -df "$f" | pvalue -r -h -H -df -pXYZ -y 256 +x 256 > "$T/xyz.hdr"
    y1=$(pvalue -h -H -d -b "$T/xyz.hdr" | sed -n 777p | awk '{print $1}')
    y2=$(pvalue -h -H -d "$T/xyz.hdr" | sed -n 777p | awk '{print $2}')
    y3=$(pvalue -h -H -d -b -O "$T/xyz.hdr" | sed -n 777p)
    if getinfo < "$T/xyz.hdr" | grep -q '^FORMAT=32-bit_rle_xyze$' && [ "$y1" = "$y2" ] &&
       close "$(awk -v y="$y3" 'BEGIN{print y*179}')" "$y1" 0.002; then
        pass pvalue_xyze; else fail pvalue_xyze "$y1 $y2 $y3"; fi
    # getinfo +d -c passes the resolution string to the command's output
    if getinfo +d -c cat < "$f" | getinfo - | cmp -s - <(getinfo - < "$f"); then
        pass getinfo_command_resolution; else fail getinfo_command_resolution; fi
fi

# --- bad input
check_fails getinfo_missing_file "cannot open" getinfo "$T/nonexistent.hdr"
printf '\001\002\003binary' > "$T/garbage"
check_fails getinfo_bad_header "bad header" getinfo "$T/garbage"
check_fails getinfo_strip_bad "bad header" sh -c "getinfo - < '$T/garbage'"
check_fails pvalue_not_picture "garbage.*(header|Radiance)" pvalue "$T/garbage"
printf '#?RADIANCE\nFORMAT=ascii\n\n-Y 2 +X 2\n1 2 3\n' > "$T/ascii.hdr"
check_fails pvalue_wrong_format "FORMAT=ascii" pvalue "$T/ascii.hdr"
printf '#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2000000000 +X 2000000000\n' > "$T/huge.hdr"
check_fails pvalue_absurd_size "too large|out of range" pvalue "$T/huge.hdr"
printf '#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 3 Z 3\n' > "$T/badres.hdr"
check_fails pvalue_bad_resolution "bad resolution string" pvalue "$T/badres.hdr"
head -c $(( $(wc -c < "$T/ramp.hdr") - 50 )) "$T/ramp.hdr" > "$T/trunc.hdr"
check_fails pvalue_truncated "byte offset [0-9]+: unexpected end of data" pvalue "$T/trunc.hdr"
check_fails pvalue_reverse_no_resolution "missing resolution" sh -c "printf '1 2 3\n' | pvalue -r -h -H -d"
check_fails pvalue_reverse_short_input "end of data" sh -c "printf '1 2 3\n' | pvalue -r -h -d -y 2 +x 2"
check_fails pvalue_reverse_bad_number "x7" sh -c "printf '1 2 x7\n' | pvalue -r -h -d -y 1 +x 1"
check_fails pvalue_reverse_wrong_format "wrong input format" sh -c "pvalue -h -H -df '$T/ramp.hdr' | pvalue -r -H -df -y 30 +x 40 '$T/ascii.hdr'"
check_fails pvalue_bad_option "unknown option" pvalue -Q "$T/ramp.hdr"
check_fails pvalue_absurd_reverse "out of range" pvalue -r -h -df -y 2000000000 +x 5
