#!/bin/sh
# vwrays, rtrace output specs and formats, bad inputs of rtrace/rpict/vwrays.
. test/e2e/lib.sh

cat > "$T/room.rad" <<'EOF'
void light solar 0 0 3 1e6 1e6 1e6
solar source sun 0 0 4 0 0 1 0.533
void plastic grey 0 0 5 .5 .5 .5 0 0
grey polygon floor 0 0 12 -5 -5 0 5 -5 0 5 5 0 -5 5 0
EOF

# vwrays: count, ascii layout, float size, fisheye corner outside a 360 view
vwrays -vtv -vp 0 0 1 -vd 0 0 -1 -vu 0 1 0 -vh 40 -vv 40 -x 8 -y 4 > "$T/v.txt" 2>"$T/err"
n=$(wc -l < "$T/v.txt"); nw=$(awk '{n+=NF} END{print n}' "$T/v.txt")
if [ "$n" -eq 16 ] && [ "$nw" -eq 96 ]; then pass vwrays_ascii; else fail vwrays_ascii "$n lines $nw words"; fi
# -c N: every pixel N times; with -pj the first ray of each pixel is the one of the run without -c
# and the other N-1 are jittered apart (inside the pixel); without -pj N identical rays
vwrays -vtv -vp 0 0 1 -vd 0 0 -1 -vu 0 1 0 -vh 40 -vv 40 -x 8 -y 4 -pj 0.7 > "$T/v1.txt"
vwrays -vtv -vp 0 0 1 -vd 0 0 -1 -vu 0 1 0 -vh 40 -vv 40 -x 8 -y 4 -pj 0.7 -c 3 > "$T/v3.txt"
vwrays -vtv -vp 0 0 1 -vd 0 0 -1 -vu 0 1 0 -vh 40 -vv 40 -x 8 -y 4 -c 2 > "$T/v2.txt"
if [ "$(wc -l < "$T/v3.txt")" -eq 48 ] && [ "$(awk 'NR % 3 == 1' "$T/v3.txt")" = "$(cat "$T/v1.txt")" ] &&
   [ "$(awk 'NR % 3 == 1' "$T/v3.txt" | sort -u | wc -l)" -eq 16 ] && [ "$(sort -u "$T/v3.txt" | wc -l)" -eq 48 ] &&
   [ "$(awk 'NR % 2 == 1' "$T/v2.txt")" = "$(awk 'NR % 2 == 0' "$T/v2.txt")" ]; then pass vwrays_repeat
else fail vwrays_repeat "expected 48 rays (16 pixels), the first of each pixel as without -c, the others distinct; -c 2 without -pj: pairs"; fi
check_fails vwrays_repeat_range "repeat count 0 out of range" vwrays -vtv -vh 40 -vv 40 -x 4 -y 4 -c 0
check vwrays_dims sh -c "vwrays -d -vtv -vh 40 -vv 20 -x 400 -y 400 | grep -qx -- '-x 400 -y 194'"
vwrays -ff -vta -vh 360 -vv 360 -x 16 -y 16 > "$T/v.f"
if [ "$(wc -c < "$T/v.f")" -eq $((16 * 16 * 24)) ]; then pass vwrays_float; else fail vwrays_float "size $(wc -c < "$T/v.f")"; fi
first=$(vwrays -vta -vh 360 -vv 360 -x 16 -y 16 | head -1 | awk '{print $4, $5, $6}')
if [ "$first" = "0.000000e+00 0.000000e+00 0.000000e+00" ]; then pass vwrays_outside_zero; else fail vwrays_outside_zero "$first"; fi

# vwrays | rtrace: the floor straight below is lit by the sun
vwrays -vtv -vp 0 0 1 -vd 0 0 -1 -vu 0 1 0 -vh 20 -vv 20 -x 4 -y 4 -ff |
    rtrace -h -ffa -ovdpnLm -ab 0 "$T/room.rad" > "$T/r.txt" 2>"$T/err"
# value 0.5/pi * 1e6 * omega (omega of a 0.533 degree disk)
want=$(awk 'BEGIN{pi=atan2(0,-1); om=2*pi*(1-cos(0.2665*pi/180)); printf "%.6g", 0.5/pi*1e6*om}')
got=$(head -1 "$T/r.txt" | awk '{print $1}')
nf=$(head -1 "$T/r.txt" | awk '{print NF}')
if [ "$nf" -eq 14 ] && close "$got" "$want" 1e-5 && head -1 "$T/r.txt" | awk '{exit !($NF=="grey" && $9>-1e-9 && $9<1e-9)}'; then
    pass rtrace_outspec
else fail rtrace_outspec "$(head -1 "$T/r.txt") (want value $want)"; fi

# -fad double output: 3 doubles per ray
printf '0 0 1 0 0 -1\n0 0 1 0 0 -1\n' | rtrace -h -fad -ab 0 "$T/room.rad" > "$T/d.bin"
if [ "$(wc -c < "$T/d.bin")" -eq 48 ]; then pass rtrace_double; else fail rtrace_double "$(wc -c < "$T/d.bin") bytes"; fi

# -h+ with binary output: NCOMP, BigEndian= (the host's order) and FORMAT in Radiance's rtrace
# order, the data aligned after the padded FORMAT line; ASCII output has no BigEndian= line
be=$( [ "$(printf '\001\000' | od -An -tu2 | tr -d ' ')" = 1 ] && echo 0 || echo 1)
printf '0 0 1 0 0 -1\n0 0 1 0 0 -1\n' | rtrace -fad -ab 0 "$T/room.rad" > "$T/dh.bin"
vars=$(getinfo < "$T/dh.bin" | grep -E '^(NCOMP|BigEndian|FORMAT)=' | sed 's/ *$//' | tr '\n' '|')
hb=$(( $(wc -c < "$T/dh.bin") - 48 ))
if [ "$vars" = "NCOMP=3|BigEndian=$be|FORMAT=double|" ] && [ $((hb % 8)) -eq 0 ] &&
   tail -c 48 "$T/dh.bin" | cmp -s - "$T/d.bin"; then pass rtrace_header_binary
else fail rtrace_header_binary "variables '$vars' (want NCOMP=3|BigEndian=$be|FORMAT=double|), header $hb bytes"; fi
printf '0 0 1 0 0 -1\n' | rtrace -ab 0 "$T/room.rad" > "$T/ah.txt"
if getinfo < "$T/ah.txt" | grep -q '^FORMAT=ascii' && ! grep -q '^BigEndian=' "$T/ah.txt"; then pass rtrace_header_ascii
else fail rtrace_header_ascii "$(getinfo < "$T/ah.txt" | tr '\n' '|')"; fi

# errors: clear message, non-zero exit, no crash
check_fails missing_scene "nothere.rad" rtrace -ab 0 "$T/nothere.rad"
check_fails no_scene "no scene" rtrace -ab 0
printf 'void plastic p 0 0 4 1 1 1 0\np polygon x 0 0 9 0 0 0 1 0 0 0 1 0\n' > "$T/badargs.rad"
check_fails bad_arguments "badargs.rad:1" sh -c "echo 0 0 0 0 0 1 | rtrace '$T/badargs.rad'"
printf 'void dielectric d 0 0 5 1 1 1 1.5 0\nd sphere s 0 0 4 0 0 0 1\n' > "$T/diel.rad"
check_fails unsupported_material "diel.rad:1.*dielectric.*not supported" sh -c "echo 0 0 0 0 0 1 | rtrace '$T/diel.rad'"
printf 'void plastic p 0 0 5 .5 .5 .5 0 0\nvoid antimatter a 1 p 0 0\na sphere s 0 0 4 0 0 0 1\n' > "$T/anti.rad"
check_fails antimatter "anti.rad:2.*antimatter" sh -c "echo 0 0 0 0 0 1 | rtrace '$T/anti.rad'"
check_fails incomplete_ray "incomplete ray" sh -c "printf '0 0 1 0 0\n' | rtrace -ab 0 '$T/room.rad'"
check_fails bad_number "bogus" sh -c "printf '0 0 1 0 0 bogus\n' | rtrace -ab 0 '$T/room.rad'"
check_fails short_float_ray "incomplete ray" sh -c "printf 'abcdefgh' | rtrace -ff -ab 0 '$T/room.rad'"
check_fails bad_outspec "not supported" rtrace -oq "$T/room.rad"
check_fails bad_format "option -fz" rtrace -fz "$T/room.rad"
check_fails bad_view_type "view type" rpict -vtq "$T/room.rad"
check_fails bad_view_file "nope.vf" rpict -vf "$T/nope.vf" "$T/room.rad"
check_fails parallel_up "parallel" rpict -vd 0 0 1 -vu 0 0 1 "$T/room.rad"
check_fails absurd_size "out of range" rpict -x 2000000 -y 10 "$T/room.rad"
check_fails vwrays_bad "expected" vwrays -vp 1 2

# rpict: same picture with 1 or 2 threads (pixels after the header)
for n in 1 2; do
    rpict -n $n -vtv -vp 0 0 2 -vd 0 0 -1 -vu 0 1 0 -vh 60 -vv 60 -x 24 -y 24 -ab 1 -ad 16 "$T/room.rad" 2>/dev/null |
        awk 'h==0 && /^$/ {h=1; next} h==1' > "$T/p$n.bin"
done
if [ -s "$T/p1.bin" ] && cmp -s "$T/p1.bin" "$T/p2.bin"; then pass rpict_threads_deterministic
else fail rpict_threads_deterministic "pictures differ or are empty"; fi
# a view file that names itself through -vf is refused, not recursed into (fuzzing finding)
printf -- '-vf %s -vp 0 0 0\n' "$T/selfview.vf" > "$T/selfview.vf"
check_fails view_file_names_itself "nested deeper than 16 through -vf" vwrays -vf "$T/selfview.vf" -x 2 -y 2 -fa
