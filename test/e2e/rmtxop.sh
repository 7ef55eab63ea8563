#!/bin/sh
# End-to-end tests of rmtxop: conversions, transpose, products of the
# reference matrices, component transforms, element operations, errors.
. test/e2e/lib.sh
command -v rmtxop >/dev/null || { fail setup "rmtxop not on PATH"; exit 0; }
B=$REF/scenes/box
if ! have_ref scenes/box; then skip all "reference folder $REF/scenes/box not found"; exit 0; fi

# data part of a matrix file (after the first empty line)
data() { sed '1,/^$/d' "$1"; }
# header variable
hvar() { sed -n "/^\$/q; s/^$2=//p" "$1" | tr -d ' '; }
# numcmp A B RTOL ATOL: compare the numbers of two ascii data files
numcmp() {
    data "$1" | tr -s ' \t' '\n\n' | sed '/^$/d' > "$T/n1"
    data "$2" | tr -s ' \t' '\n\n' | sed '/^$/d' > "$T/n2"
    [ "$(wc -l < "$T/n1")" -eq "$(wc -l < "$T/n2")" ] || { echo "value counts differ"; return 1; }
    paste "$T/n1" "$T/n2" | awk -v rt="$3" -v at="$4" '
        { d = $1 - $2; if (d < 0) d = -d; m = $2 < 0 ? -$2 : $2
          if (d > at + rt * m) { bad++; if (bad < 4) print "differ:", NR, $1, $2 } }
        END { if (NR == 0) { print "no values"; exit 1 } exit bad > 0 }'
}

S=$B/a3_sky_mf1_3h.smx      # 146 x 3 x 3 float, Radiance rmtxop output

# --- conversions -----------------------------------------------------
rmtxop -fa "$S" > "$T/s.fa" && rmtxop -ff "$S" > "$T/s.ff" && rmtxop -fd "$S" > "$T/s.fd" \
    && rmtxop -fc "$S" > "$T/s.fc" || fail convert "rmtxop failed"
check header_ascii test "$(hvar "$T/s.fa" NROWS)x$(hvar "$T/s.fa" NCOLS)x$(hvar "$T/s.fa" NCOMP)/$(hvar "$T/s.fa" FORMAT)" = "146x3x3/ascii"
check header_double test "$(hvar "$T/s.fd" FORMAT)/$(hvar "$T/s.fd" BigEndian)" = "double/0"
# float -> float keeps the bytes of the data
check float_data_identical cmp -s "$T/s.ff" "$S" -i "$(($(wc -c < "$T/s.ff") - 146*3*3*4)):$(($(wc -c < "$S") - 146*3*3*4))"
check float_size test "$(wc -c < "$T/s.ff")" -ge $((146*3*3*4))
# double and float back to ascii: the same text as the direct conversion
rmtxop -fa "$T/s.fd" > "$T/s.fd.fa"; rmtxop -fa "$T/s.ff" > "$T/s.ff.fa"
data "$T/s.fa" > "$T/d0"; data "$T/s.fd.fa" > "$T/d1"; data "$T/s.ff.fa" > "$T/d2"
check double_to_ascii_same cmp -s "$T/d1" "$T/d0"
check float_to_ascii_same cmp -s "$T/d2" "$T/d0"
# ascii -> float -> ascii within float precision
rmtxop -ff "$T/s.fa" > "$T/s.fa.ff"; rmtxop -fa "$T/s.fa.ff" > "$T/s.fa.ff.fa"
check ascii_float_ascii numcmp "$T/s.fa.ff.fa" "$T/s.fa" 1.2e-7 0
# picture: a valid RGBE file with a resolution string, values within RGBE precision
check picture_header sh -c "grep -q '^FORMAT=32-bit_rle_rgbe\$' '$T/s.fc' && grep -aq '^-Y      146 +X        3\$' '$T/s.fc'"
rmtxop -fa "$T/s.fc" > "$T/s.fc.fa"
check picture_values numcmp "$T/s.fc.fa" "$T/s.fa" 0.008 1e-30
# a Radiance picture (RLE) through rmtxop -fc: pixel data byte for byte
P=$B/a2_clear_fish.hdr
rmtxop -fc "$P" > "$T/p.hdr"
check picture_bytes_identical cmp -s -i "$(sed -n '1,/^$/p' "$P" | wc -c):$(sed -n '1,/^$/p' "$T/p.hdr" | wc -c)" "$P" "$T/p.hdr"
check picture_header_inherited grep -aq '^VIEW= -vta' "$T/p.hdr"
# one component written as a grey picture
rmtxop -fc -c 0.2 0.7 0.1 "$S" > "$T/grey.hdr"
rmtxop -fa "$T/grey.hdr" > "$T/grey.fa"
check grey_picture sh -c "sed '1,/^\$/d' '$T/grey.fa' | tr '\t' '\n' | awk 'NF==3 && (\$1!=\$2 || \$2!=\$3) {bad++} END {exit bad>0}'"
rmtxop -fa -c 0.2 0.7 0.1 "$S" > "$T/grey.ref"
rmtxop -fa -c 0 1 0 "$T/grey.hdr" > "$T/grey.g"
check grey_values numcmp "$T/grey.g" "$T/grey.ref" 0.008 1e-30
# stdin and !command inputs
rmtxop -fa - < "$S" > "$T/s.stdin" && check stdin_input numcmp "$T/s.stdin" "$T/s.fa" 0 0
rmtxop -fa "!cat $S" > "$T/s.cmd" && check command_input numcmp "$T/s.cmd" "$T/s.fa" 0 0
# gzip input (reference year sky, 146 x 8760)
if [ -f "$REF/sky/daymtx/chicago_year_mf1.mtx.gz" ]; then
    rmtxop -ff "$REF/sky/daymtx/chicago_year_mf1.mtx.gz" > "$T/year.ff"
    check gzip_input test "$(hvar "$T/year.ff" NROWS)x$(hvar "$T/year.ff" NCOLS)" = "146x8760"
fi

# --- transpose ---------------------------------------------------------
rmtxop -fa -t "$S" > "$T/st.fa"
check transpose_dims test "$(hvar "$T/st.fa" NROWS)x$(hvar "$T/st.fa" NCOLS)" = "3x146"
# element (row 50, col 2) of S = element (row 2, col 50) of S^T, green component
a=$(data "$T/s.fa" | sed -n 51p | awk -F'\t' '{print $3}' | awk '{print $2}')
b=$(data "$T/st.fa" | sed -n 3p | awk -F'\t' '{print $51}' | awk '{print $2}')
check transpose_value test -n "$a" -a "$a" = "$b"
rmtxop -fa -t "$T/st.fa" > "$T/stt.fa"
check transpose_twice numcmp "$T/stt.fa" "$T/s.fa" 0 0

# --- products of reference matrices ------------------------------------
rmtxop -ff "$B/a3_V_sensors.vmx" "$B/a3_D.dmx" "$B/a3_sky_mf1.smx" > "$T/vds.ff"
check product_dims test "$(hvar "$T/vds.ff" NROWS)x$(hvar "$T/vds.ff" NCOLS)x$(hvar "$T/vds.ff" NCOMP)" = "28x72x3"
# a chain ending in a vector is evaluated from the right: same values
rmtxop -fd "$B/a3_V_sensors.vmx" "$B/a3_D.dmx" > "$T/vd.fd"
rmtxop -fa "$T/vd.fd" "$B/a4_sunvec_mf1_0101_1030.vec" > "$T/vdv.ltr"
rmtxop -fa "$B/a3_V_sensors.vmx" "$B/a3_D.dmx" "$B/a4_sunvec_mf1_0101_1030.vec" > "$T/vdv.chain"
check chain_dims test "$(hvar "$T/vdv.chain" NROWS)x$(hvar "$T/vdv.chain" NCOLS)" = "28x1"
check chain_equals_left_to_right numcmp "$T/vdv.chain" "$T/vdv.ltr" 1e-6 1e-20
check product_no_inherited sh -c "sed -n 2p '$T/vds.ff' | grep -q '^rmtxop -ff '"
# the product as Radiance computed it (a3_sky_mf1_3h.smx)
(cd "$B" && rmtxop -ff a3_sky_mf1.smx a3_select3.mtx) > "$T/sel.ff"
check product_equals_radiance cmp -s "$T/sel.ff" "$S"
check_fails product_dim_message "columns of the first \(146\) must equal the rows of the second \(145\)" \
    rmtxop "$B/a3_D.dmx" "$B/a3_D.dmx"

# --- component transform and scaling -----------------------------------
rmtxop -fa -c 47.4 119.9 11.6 "$S" > "$T/lux.fa"
check lum_ncomp test "$(hvar "$T/lux.fa" NCOMP)" = 1
data "$T/s.fa" | awk -F'\t' '{ for (i = 1; i < NF; i++) { split($i, c, " "); printf " %.7e\t", 47.4*c[1] + 119.9*c[2] + 11.6*c[3] } printf "\n" }' > "$T/lux.awk"
printf '#?RADIANCE\n\n' | cat - "$T/lux.awk" > "$T/lux.ref"
check lum_values numcmp "$T/lux.fa" "$T/lux.ref" 2e-7 1e-30
# 179 * the Y row of Radiance 6.1's RGB -> XYZ matrix (nominal primaries,
# equal-energy white 1/3 1/3; Radiance's rmtxop/rcomb -c y of an identity
# matrix print 2.6510581e-01 6.7010581e-01 6.4788356e-02)
rmtxop -fa -c Y "$S" > "$T/Y.fa"
data "$T/s.fa" | awk -F'\t' '{ for (i = 1; i < NF; i++) { split($i, c, " "); printf " %.7e\t", 179*(0.26510581*c[1] + 0.67010581*c[2] + 0.064788356*c[3]) } printf "\n" }' > "$T/Y.awk"
printf '#?RADIANCE\n\n' | cat - "$T/Y.awk" > "$T/Y.ref"
check lum_symbol_Y numcmp "$T/Y.fa" "$T/Y.ref" 1e-6 1e-30
# colour spaces: -c XYZ of a picture writes an XYZE picture; -c RGB brings it back
P3=$B/a3_img/skysun_0.hdr
rmtxop -c XYZ "$P3" > "$T/xyz.hdr"
check xyz_picture grep -aq '^FORMAT=32-bit_rle_xyze$' "$T/xyz.hdr"
rmtxop -fa -c RGB "$T/xyz.hdr" > "$T/back.fa"; rmtxop -fa "$P3" > "$T/orig.fa"
check xyz_rgb_round_trip le "$(maxrel "$T/back.fa" "$T/orig.fa" 0.01)" 0.03    # two RGBE encodings
rmtxop -fa -c Y "$T/xyz.hdr" > "$T/y1.fa"; rmtxop -fa -c Y "$P3" > "$T/y2.fa"
check xyz_Y_channel le "$(maxrel "$T/y1.fa" "$T/y2.fa" 0.01)" 0.01
printf -- '-fa -c 47.4 119.9 11.6\n' > "$T/opts.txt"
rmtxop @"$T/opts.txt" "$S" > "$T/luxat.fa"
check at_file_options numcmp "$T/luxat.fa" "$T/lux.fa" 0 0
rmtxop -fa -s 2 "$S" > "$T/s2.fa"
rmtxop -fa "$S" + "$S" > "$T/ss.fa"
check scale_equals_sum numcmp "$T/ss.fa" "$T/s2.fa" 0 0
rmtxop -fa "$S" -s 0.5 0.25 2 > "$T/sc.fa"     # trailing -s applies to the result
a=$(data "$T/s.fa" | sed -n 60p | awk -F'\t' '{print $2}')
b=$(data "$T/sc.fa" | sed -n 60p | awk -F'\t' '{print $2}')
check scale_per_component sh -c "echo '$a' '$b' | awk '{d=\$4-0.5*\$1; e=\$5-0.25*\$2; f=\$6-2*\$3; exit !(d*d+e*e+f*f <= 1e-12*(\$1*\$1+\$2*\$2+\$3*\$3) && \$1 != 0)}'"

# --- element product / quotient ----------------------------------------
rmtxop -fa "$S" '*' "$S" > "$T/sq.fa"
data "$T/s.fa" | awk -F'\t' '{ for (i = 1; i < NF; i++) { split($i, c, " "); printf " %.7e %.7e %.7e\t", c[1]*c[1], c[2]*c[2], c[3]*c[3] } printf "\n" }' > "$T/sq.awk"
printf '#?RADIANCE\n\n' | cat - "$T/sq.awk" > "$T/sq.ref"
check element_product numcmp "$T/sq.fa" "$T/sq.ref" 3e-7 1e-30
rmtxop -fa "$S" / "$S" > "$T/q.fa"
check quotient_values sh -c "sed '1,/^\$/d' '$T/q.fa' | tr -s ' \t' '\n\n' | sed '/^\$/d' | sort -u | tr '\n' ' ' | grep -Eq '^1\.0000000e\+00 \$'"
printf '#?RADIANCE\nNROWS=1\nNCOLS=3\nNCOMP=1\nFORMAT=ascii\n\n6 3 5\n' > "$T/num.mtx"
printf '#?RADIANCE\nNROWS=1\nNCOLS=3\nNCOMP=1\nFORMAT=ascii\n\n2 0 -5\n' > "$T/den.mtx"
rmtxop -fa "$T/num.mtx" / "$T/den.mtx" > "$T/q2.fa" 2> "$T/q2.err"
check quotient_zero_warning grep -q "warning: .*1 zero divisor" "$T/q2.err"
check quotient_zero_values test "$(data "$T/q2.fa")" = "$(printf ' 3.0000000e+00\t 0.0000000e+00\t -1.0000000e+00\t')"

# --- errors --------------------------------------------------------------
printf '#?RADIANCE\nNROWS=3\nNCOLS=4\nNCOMP=3\nFORMAT=float\n\n0123456789' > "$T/trunc.mtx"
check_fails truncated "trunc.mtx: byte offset .*needs 144 bytes" rmtxop "$T/trunc.mtx"
printf '#?RADIANCE\nNROWS=2000000000\nNCOLS=2000000000\nNCOMP=3\nFORMAT=float\n\n' > "$T/huge.mtx"
check_fails huge "huge.mtx: .*exceeds the limit" rmtxop "$T/huge.mtx"
printf '#?RADIANCE\nNROWS=-1\nNCOLS=2\nFORMAT=ascii\n\n' > "$T/neg.mtx"
check_fails negative_rows "neg.mtx: NROWS=-1" rmtxop "$T/neg.mtx"
printf '#?RADIANCE\nNROWS=1\nNCOLS=2\nNCOMP=1\nFORMAT=ascii\n\n1 abc\n' > "$T/word.mtx"
check_fails non_numeric 'word.mtx: line 7: .*"abc"' rmtxop "$T/word.mtx"
printf '#?RADIANCE\nNROWS=1\nNCOLS=2\nFORMAT=floats\n\n' > "$T/fmt.mtx"
check_fails wrong_format "fmt.mtx: .*FORMAT=floats" rmtxop "$T/fmt.mtx"
check_fails missing_file "nonexistent.mtx" rmtxop "$T/nonexistent.mtx"
# XML BSDF inputs: Klems matrices equal Radiance's rmtxop output byte for byte.
if rmtxop -ff "$B/glass_klems.xml" > "$T/glass.ff" 2> "$T/glass.err"; then
    check xml_dims test "$(hvar "$T/glass.ff" NROWS)x$(hvar "$T/glass.ff" NCOLS)x$(hvar "$T/glass.ff" NCOMP)" = "145x145x3"
    if have_ref bsdf; then
        for c in cfs1/cfs1_klems glazing/glazing_klems cfs3/cfs3_klems; do
            for w in T Rf Rb; do
                case $w in T) o= ;; Rf) o=-rf ;; Rb) o=-rb ;; esac
                (cd "$REF/bsdf" && rmtxop -fa $o $c.xml) > "$T/xml.out" 2>&1
                check "xml_$(basename $c)_$w" cmp -s "$T/xml.out" "$REF/bsdf/${c}_$w.mtx"
            done
        done
    fi
else
    fail xml_read "$(cat "$T/glass.err")"
fi
# --- what three-phase scripts do ------------------------------------------
# V T D S in one rmtxop with the BSDF XML as T (products of four matrices):
# Radiance's dctimestep result on the same files (a3_res_sensors_skysun.mtx).
if (cd "$B" && rmtxop -fa a3_V_sensors.vmx glass_klems.xml a3_D.dmx a3_sky_mf1.smx) > "$T/vtds.fa" 2> "$T/vtds.err"; then
    check 3pm_vtds_dims test "$(hvar "$T/vtds.fa" NROWS)x$(hvar "$T/vtds.fa" NCOLS)x$(hvar "$T/vtds.fa" NCOMP)" = "28x72x3"
    check 3pm_vtds_equals_radiance numcmp "$T/vtds.fa" "$B/a3_res_sensors_skysun.mtx" 1e-5 1e-9
    # explicit '.' operators and a -c luminous-efficacy weighting of the result
    (cd "$B" && rmtxop -fa a3_V_sensors.vmx . glass_klems.xml . a3_D.dmx . a3_sky_mf1.smx -c 47.4 119.9 11.6) > "$T/ill.fa"
    data "$T/vtds.fa" | awk -F'\t' '{ for (i = 1; i < NF; i++) { split($i, c, " "); printf " %.7e\t", 47.4*c[1] + 119.9*c[2] + 11.6*c[3] } printf "\n" }' > "$T/ill.awk"
    printf '#?RADIANCE\n\n' | cat - "$T/ill.awk" > "$T/ill.ref"
    check 3pm_dot_operators_and_c numcmp "$T/ill.fa" "$T/ill.ref" 1e-6 1e-9
    # D^T transposed back: (D^T)^T S == D S
    (cd "$B" && rmtxop -fa -t a3_D.dmx -t) > "$T/dtt.fa"
    (cd "$B" && rmtxop -fa a3_D.dmx) > "$T/d.fa"
    check transpose_of_transpose numcmp "$T/dtt.fa" "$T/d.fa" 0 0
else
    fail 3pm_vtds "$(cat "$T/vtds.err")"
fi
# difference as 3PM scripts write it (A + -s -1 B): zero for A = B; A - B/2 = A/2
rmtxop -fa "$S" + -s -1 "$S" > "$T/diff0.fa"
check difference_zero sh -c "sed '1,/^\$/d' '$T/diff0.fa' | tr -s ' \t' '\n\n' | sed '/^\$/d' | awk '\$1 != 0 {bad++} END {exit bad > 0 || NR == 0}'"
rmtxop -fa "$S" + -s -0.5 "$S" > "$T/diffh.fa"
rmtxop -fa -s 0.5 "$S" > "$T/half.fa"
check difference_half numcmp "$T/diffh.fa" "$T/half.fa" 1e-7 1e-30
check_fails bad_coefs "not a multiple" rmtxop -c 1 2 "$S"
check_fails no_operand "no input matrix" rmtxop -fa
check_fails dangling_operator "operator must be followed" rmtxop "$S" +
check_fails unknown_option "unknown option" rmtxop -q "$S"
printf '#?RADIANCE\nNROWS=3\nNCOLS=1\nNCOMP=2\nFORMAT=ascii\n\n1 2\n3 4\n5 6\n' > "$T/c2.mtx"
check_fails ncomp_mismatch "component counts differ \\(3 and 2" rmtxop "$S" "$T/c2.mtx"
check_fails picture_ncomp "picture" rmtxop -fc "$T/c2.mtx"
exit 0
