# End-to-end tests of hdr2exr and exr2hdr on a reference picture made by
# Radiance (rpict).  Run from the project root with build/bin on PATH.
. test/e2e/lib.sh

PIC=$REF/scenes/box/a2_clear_fish.hdr
PIC2=$REF/scenes/box/a2_overcast_fish.hdr

# ---- bad usage: exit 1 with the usage message ----
check_fails hdr2exr_no_args 'usage: hdr2exr' hdr2exr
check_fails hdr2exr_bad_comp 'unknown compression.*usage: hdr2exr|usage: hdr2exr' hdr2exr -c lzw in.hdr "$T/x.exr"
check_fails hdr2exr_too_many 'usage: hdr2exr' hdr2exr a.hdr b.hdr c.exr
check_fails exr2hdr_no_args 'usage: exr2hdr' exr2hdr
check_fails exr2hdr_bad_opt 'usage: exr2hdr' exr2hdr -Q x.exr
for p in hdr2exr exr2hdr; do
    "$p" >/dev/null 2>&1; rc=$?
    if [ "$rc" -eq 1 ]; then pass "${p}_usage_status"; else fail "${p}_usage_status" "exit status $rc, expected 1"; fi
done
check_fails exr2hdr_missing_file 'nonexistent\.exr' exr2hdr "$T/nonexistent.exr" "$T/n.hdr"

if [ ! -f "$PIC" ]; then
    skip reference_picture "$PIC not found"
    exit 0
fi

# Byte offsets (0-based) of the resolution line and of the pixel data.
res_offset() {
    LC_ALL=C awk 'BEGIN { n = 0 } /^[-+][XY] +[0-9]+ [-+][XY] +[0-9]+$/ { print n; exit } { n += length($0) + 1 }' "$1"
}
data_offset() {
    LC_ALL=C awk 'BEGIN { n = 0 } { n += length($0) + 1 } /^[-+][XY] +[0-9]+ [-+][XY] +[0-9]+$/ { print n; exit }' "$1"
}
# same_pixels A B : the RLE pixel data of two pictures are byte-identical
same_pixels() {
    oa=$(data_offset "$1"); ob=$(data_offset "$2")
    [ -n "$oa" ] && [ -n "$ob" ] || return 1
    tail -c +$((oa + 1)) "$1" > "$T/pa.bin"; tail -c +$((ob + 1)) "$2" > "$T/pb.bin"
    cmp -s "$T/pa.bin" "$T/pb.bin"
}

# ---- float: picture -> EXR -> picture keeps the RGBE values exactly, so the
# re-encoded scanlines equal Radiance's byte for byte ----
for c in zip piz none; do
    if hdr2exr -c "$c" "$PIC" "$T/f_$c.exr" 2>"$T/err" && exr2hdr "$T/f_$c.exr" "$T/f_$c.hdr" 2>>"$T/err"; then
        if same_pixels "$PIC" "$T/f_$c.hdr"; then pass "float_${c}_exact"
        else fail "float_${c}_exact" "pixel data differ from the reference"; fi
    else
        fail "float_${c}_exact" "$(head -2 "$T/err" | tr '\n' ' ')"
    fi
done

# determinism: same input -> byte-identical EXR
# (the same command line too: it is recorded in the file)
mv "$T/f_piz.exr" "$T/f_piz1.exr"
hdr2exr -c piz "$PIC" "$T/f_piz.exr" 2>/dev/null
if cmp -s "$T/f_piz.exr" "$T/f_piz1.exr"; then pass deterministic; else fail deterministic "two runs differ"; fi

# stdin / stdout
if hdr2exr -half < "$PIC" - > "$T/s.exr" 2>"$T/err" && exr2hdr - < "$T/s.exr" > "$T/s.hdr" 2>>"$T/err" \
   && [ "$(data_offset "$T/s.hdr")" -gt 0 ] 2>/dev/null; then pass stdin_stdout
else fail stdin_stdout "$(head -2 "$T/err" | tr '\n' ' ')"; fi

# ---- provenance: the EXR carries the Radiance header; exr2hdr puts it back
# with both command lines and SOFTWARE ----
H=$T/f_zip.hdr
if grep -a -q '^rpict -vf fish.vf' "$H" && grep -a -q '^VIEW= -vta' "$H" \
   && grep -a -q "^hdr2exr -c zip $PIC" "$H" && grep -a -q "^exr2hdr $T/f_zip.exr" "$H" \
   && grep -a -q '^SOFTWARE= heliodon' "$H" && grep -a -q '^FORMAT=32-bit_rle_rgbe' "$H"; then
    pass provenance_header
else
    fail provenance_header "$(head -c 600 "$H" | tr '\n' '|')"
fi
if [ "$(grep -a -c '^FORMAT=' "$H")" -eq 1 ]; then pass single_format_line
else fail single_format_line "$(grep -a -c '^FORMAT=' "$H") FORMAT lines"; fi
if grep -a -q 'heliodonHeader' "$T/f_zip.exr" && grep -a -q 'rpict -vf fish.vf' "$T/f_zip.exr"; then
    pass exr_header_attribute
else fail exr_header_attribute "no heliodonHeader attribute in the EXR"; fi

# ---- layers: two pictures in one EXR, each extracted exactly ----
if [ -f "$PIC2" ]; then
    if hdr2exr -c piz -L clear "$PIC" -L overcast "$PIC2" "$T/two.exr" 2>"$T/err" \
       && exr2hdr -l overcast "$T/two.exr" "$T/two_o.hdr" 2>>"$T/err" \
       && exr2hdr -l clear "$T/two.exr" "$T/two_c.hdr" 2>>"$T/err" \
       && same_pixels "$PIC2" "$T/two_o.hdr" && same_pixels "$PIC" "$T/two_c.hdr"; then
        pass layers_exact
    else fail layers_exact "$(head -2 "$T/err" | tr '\n' ' ')"; fi
    # each layer's header goes with it
    if grep -a -q '^rpict' "$T/two_o.hdr" && grep -a -q '^oconv .*sky_overcast' "$T/two_o.hdr" \
       && ! grep -a -q 'sky_clear' "$T/two_o.hdr" && grep -a -q '^hdr2exr -c piz -L clear' "$T/two_o.hdr"; then
        pass layer_provenance
    else fail layer_provenance "$(head -c 600 "$T/two_o.hdr" | tr '\n' '|')"; fi
    check_fails layer_missing 'layers: clear, overcast' exr2hdr "$T/two.exr" "$T/none.hdr"
    check_fails layer_unknown 'no channels sunny\.R' exr2hdr -l sunny "$T/two.exr" "$T/none.hdr"
    if [ ! -e "$T/none.hdr" ]; then pass no_output_on_error; else fail no_output_on_error "$T/none.hdr left behind"; fi
else
    skip layers_exact "$PIC2 not found"
fi

# ---- bad input files ----
check_fails not_exr 'not an OpenEXR file' exr2hdr "$PIC" "$T/bad.hdr"
sz=$(wc -c < "$T/f_zip.exr")
head -c $((sz / 2)) "$T/f_zip.exr" > "$T/cut.exr"
check_fails truncated_exr 'cut\.exr: .*(corrupt|truncated)' exr2hdr "$T/cut.exr" "$T/cut.hdr"
if [ ! -e "$T/cut.hdr" ]; then pass truncated_no_output; else fail truncated_no_output "$T/cut.hdr left behind"; fi
head -c 100 "$T/f_zip.exr" > "$T/head.exr"
check_fails truncated_header 'head\.exr: ' exr2hdr "$T/head.exr" "$T/head.hdr"
check_fails not_picture "$T/f_zip.exr" hdr2exr "$T/f_zip.exr" "$T/x.exr"

# ---- interoperability with the OpenEXR C++ tools (Debian package openexr),
# when installed: they read our files, and we read their tiled / mip-mapped
# output of it ----
if command -v exrmaketiled >/dev/null 2>&1 && command -v exrheader >/dev/null 2>&1; then
    if exrheader "$T/f_zip.exr" 2>&1 | grep -q 'heliodonHeader (type string)'; then pass cxx_reads_header
    else fail cxx_reads_header "exrheader did not list heliodonHeader"; fi
    ok=1
    exrmaketiled -t 64 32 "$T/f_piz.exr" "$T/tiled.exr" >/dev/null 2>&1 || ok=0
    exrmaketiled -m -t 64 64 "$T/f_zip.exr" "$T/mip.exr" >/dev/null 2>&1 || ok=0
    for f in tiled mip; do
        [ $ok = 1 ] && exr2hdr "$T/$f.exr" "$T/$f.hdr" 2>"$T/err" && same_pixels "$PIC" "$T/$f.hdr" || ok=0
    done
    if [ $ok = 1 ]; then pass cxx_tiled_roundtrip; else fail cxx_tiled_roundtrip "$(head -2 "$T/err" | tr '\n' ' ')"; fi
    # chromaticities changed by another program: exr2hdr states them last
    if command -v exrstdattr >/dev/null 2>&1 \
       && exrstdattr -chromaticities 0.64 0.33 0.30 0.60 0.15 0.06 0.3127 0.3290 "$T/f_zip.exr" "$T/rec.exr" \
       && exr2hdr "$T/rec.exr" "$T/rec.hdr" \
       && [ "$(LC_ALL=C grep -a '^PRIMARIES=' "$T/rec.hdr" | tail -1)" = \
            "PRIMARIES= 0.6400 0.3300 0.3000 0.6000 0.1500 0.0600 0.3127 0.3290" ]; then pass cxx_chromaticities
    else fail cxx_chromaticities "$(LC_ALL=C grep -a '^PRIMARIES=' "$T/rec.hdr" 2>&1 | tr '\n' '|')"; fi
    # other compressions, written by the C++ library from a half image
    hdr2exr -half "$PIC" "$T/hh.exr" 2>/dev/null
    for z in pxr24 b44; do
        if exrmaketiled -z $z "$T/hh.exr" "$T/z_$z.exr" >/dev/null 2>&1 && exr2hdr "$T/z_$z.exr" "$T/z_$z.hdr" 2>"$T/err" \
           && [ "$(LC_ALL=C grep -a -m1 '^-Y' "$T/z_$z.hdr")" = "-Y      256 +X      256" ]; then pass "cxx_read_$z"
        else fail "cxx_read_$z" "$(head -2 "$T/err" | tr '\n' ' ')"; fi
    done
    # DWA: OpenEXRCore 3.1 cannot decode it; the error must say so
    if exrmaketiled -z dwaa "$T/hh.exr" "$T/z_dwaa.exr" >/dev/null 2>&1; then
        if exr2hdr "$T/z_dwaa.exr" "$T/z_dwaa.hdr" >"$T/err" 2>&1; then pass cxx_read_dwaa
        elif grep -q 'z_dwaa.exr: dwaa compression cannot be decoded by OpenEXRCore' "$T/err"; then pass cxx_read_dwaa_refused
        else fail cxx_read_dwaa "$(head -2 "$T/err" | tr '\n' ' ')"; fi
    fi
else
    skip cxx_interop "OpenEXR tools (exrheader, exrmaketiled) not installed"
fi

# ---- values: half precision and EXPOSURE handling (needs pvalue) ----
if command -v pvalue >/dev/null 2>&1; then
    # compare two pictures pixel by pixel: |a-b| <= tol * max(a) per pixel
    cmp_values() {  # A B TOL
        pvalue -h -H -d "$1" > "$T/va.txt" && pvalue -h -H -d "$2" > "$T/vb.txt" || return 2
        paste "$T/va.txt" "$T/vb.txt" | awk -v t="$3" '
            { m = $1; if ($2 > m) m = $2; if ($3 > m) m = $3
              for (i = 1; i <= 3; i++) { d = $i - $(i+3); if (d < 0) d = -d; if (d > t * m + 1e-30) bad++ }
              n++ }
            END { if (n == 0 || bad) { printf "%d of %d pixels differ\n", bad, n; exit 1 } }'
    }
    # half: within half precision plus one RGBE requantisation step (1/256 of the
    # largest component)
    hdr2exr -half -c piz "$PIC" "$T/h.exr" 2>"$T/err" && exr2hdr "$T/h.exr" "$T/h.hdr" 2>>"$T/err"
    check half_values cmp_values "$PIC" "$T/h.hdr" 0.004
    # PXR24 is lossless for half data
    if [ -f "$T/z_pxr24.hdr" ]; then check cxx_pxr24_values cmp_values "$PIC" "$T/z_pxr24.hdr" 0.004; fi
    # EXPOSURE: undone by default (EXR holds radiance), kept with -r
    # (pvalue prints 4 significant digits: compare within 1e-3)
    off=$(res_offset "$PIC")
    { printf '#?RADIANCE\nrpict (test)\nEXPOSURE=2.000000e+00\nFORMAT=32-bit_rle_rgbe\n\n'
      tail -c +$((off + 1)) "$PIC"; } > "$T/exp.hdr"
    hdr2exr "$T/exp.hdr" "$T/exp.exr" && exr2hdr "$T/exp.exr" "$T/exp_back.hdr"
    pvalue -h -H -d "$PIC" | awk '{ printf "%.6e %.6e %.6e\n", $1 / 2, $2 / 2, $3 / 2 }' > "$T/halfref.txt"
    pvalue -h -H -d "$T/exp_back.hdr" > "$T/expv.txt"
    if paste "$T/halfref.txt" "$T/expv.txt" | awk '{ for (i = 1; i <= 3; i++) { d = $i - $(i+3); if (d < 0) d = -d
           m = $i < 0 ? -$i : $i; if (d > 1e-3 * m + 1e-30) bad++ } } END { exit bad ? 1 : 0 }' \
       && ! grep -a -q '^EXPOSURE=' "$T/exp_back.hdr"; then pass exposure_undone
    else fail exposure_undone "values not halved or EXPOSURE line kept"; fi
    hdr2exr -r "$T/exp.hdr" "$T/expr.exr" && exr2hdr "$T/expr.exr" "$T/expr_back.hdr"
    if same_pixels "$T/exp.hdr" "$T/expr_back.hdr" && grep -a -q '^EXPOSURE=2' "$T/expr_back.hdr"; then
        pass exposure_kept_raw
    else fail exposure_kept_raw "raw values or EXPOSURE line not kept"; fi
else
    skip half_values "pvalue not built"
    skip exposure "pvalue not built"
fi
