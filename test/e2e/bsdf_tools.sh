#!/bin/sh
# checkBSDF and bsdf2klems end to end: reports against Radiance's, the
# converted XML read back, bad inputs.
. test/e2e/lib.sh

if have_ref bsdf; then
    for f in glazing/glazing_klems cfs1/cfs1_klems cfs1/cfs1_ttree cfs1/cfs1_ttree_klems \
             cfs3/cfs3_klems cfs3/cfs3_ttree cfs3/cfs3_ttree_klems; do
        n=$(basename $f)
        if checkBSDF "$REF/bsdf/$f.xml" > "$T/$n.txt" 2> "$T/$n.err"; then
            # everything but the File: line identical (lines 3-14: names,
            # type, Lambertian parts, maxima, angles, headings) ...
            sed -n '3,14p' "$T/$n.txt" > "$T/$n.got"
            sed -n '3,14p' "$REF/bsdf/$f.checkBSDF.txt" > "$T/$n.want"
            if cmp -s "$T/$n.got" "$T/$n.want"; then pass "checkBSDF_$n"
            else fail "checkBSDF_$n" "$(diff "$T/$n.got" "$T/$n.want" | head -4 | tr '\n' ' ')"; fi
            # ... and every reciprocity figure (lines 15-17) within 1
            # percentage point of Radiance's, same labels
            if paste "$T/$n.txt" "$REF/bsdf/$f.checkBSDF.txt" | sed -n '15,17p' |
               awk -F'\t' 'NF != 8 || $1 != $5 { bad = 1; next }
                           { for (k = 2; k <= 4; k++) { d = $k - $(k + 4); if (d < 0) d = -d;
                                                        if (d > 1.0) { bad = 1; print $1, $k, $(k + 4) } } }
                           END { exit bad }' > "$T/$n.rec"; then pass "checkBSDF_recip_$n"
            else fail "checkBSDF_recip_$n" "$(tr '\n' ' ' < "$T/$n.rec")"; fi
        else
            fail "checkBSDF_$n" "$(cat "$T/$n.err")"
        fi
    done
    # bsdf2klems of the anisotropic tree, read back: the room-side
    # reflection line equals Radiance's conversion (same 2.1 % Lambertian
    # part, 61.8 % max); transmission maxima within 5 points (Radiance's
    # Monte Carlo estimate is biased high by its noise, see bsdf.md)
    if bsdf2klems "$REF/bsdf/cfs1/cfs1_ttree.xml" > "$T/c1k.xml" 2> "$T/c1k.err" &&
       checkBSDF "$T/c1k.xml" > "$T/c1k.txt"; then
        pass bsdf2klems_runs
        g=$(grep '^Interior Refl	' "$T/c1k.txt" | head -1)
        w=$(grep '^Interior Refl	' "$REF/bsdf/cfs1/cfs1_ttree_klems.checkBSDF.txt" | head -1)
        [ "$g" = "$w" ] && pass bsdf2klems_rf_line || fail bsdf2klems_rf_line "got '$g' want '$w'"
        for lab in 'Int->Ext Trans' 'Ext->Int Trans'; do
            tag=$(echo "$lab" | cut -c1-3)
            g=$(grep "^$lab	" "$T/c1k.txt" | awk -F'\t' '{sub("%","",$4); print $4}')
            w=$(grep "^$lab	" "$REF/bsdf/cfs1/cfs1_ttree_klems.checkBSDF.txt" | awk -F'\t' '{sub("%","",$4); print $4}')
            if awk -v a="$g" -v b="$w" 'BEGIN{d=a-b; if(d<0)d=-d; exit !(d<=5)}'; then pass "bsdf2klems_max_$tag"
            else fail "bsdf2klems_max_$tag" "$g vs $w"; fi
        done
        grep -q 'Reflection Front' "$T/c1k.xml" && fail bsdf2klems_blocks "Reflection Front written" \
            || pass bsdf2klems_blocks
        grep -q '<!-- File produced by: bsdf2klems' "$T/c1k.xml" && pass bsdf2klems_comment \
            || fail bsdf2klems_comment "no producing command"
    else
        fail bsdf2klems_runs "$(cat "$T/c1k.err")"
    fi
    # Our conversion against Radiance's bsdf2klems output (both read by
    # rmtxop): per incident patch the hemispherical sum (column sum) and,
    # element-wise, the mean relative difference where the reference
    # exceeds 1 % of its row maximum.  Radiance averages 1024 random
    # direction pairs per patch pair; heliodon integrates the tree exactly.
    # Radiance's own run-to-run noise (same file, different seeds, measured
    # in docs/benchmarks/bsdf.md) is on CFS3 11.5 / 10 / 17 % element-wise
    # and 9-16 % on the worst patch sum (T / Rf / Rb), so against one
    # Radiance run the issue's 5 % and 1 % criteria can only hold for the
    # smooth CFS1 room-side reflection; elsewhere the bounds below are
    # those noise levels (measured: ours vs the reference 8.1 / 7.0 / 12.1 %
    # element-wise, = Radiance's noise / sqrt(2) as for a converged result).
    kcmp() {   # ours.mtx ref.mtx -> "colmean colmax elem" (percent)
        awk 'FNR == 1 { f++; hdr = 1 } hdr { if ($0 == "") { hdr = 0; r = 0 } next }
             NF { for (k = 2; k <= NF; k += 3) { v[f, r, (k - 2) / 3] = $k } nc = (NF / 3); r++; nr = r }
             END { for (i = 0; i < nc; i++) { a = b = 0; for (o = 0; o < nr; o++) { a += v[1, o, i]; b += v[2, o, i] }
                                              if (b >= 0.01) { d = (a - b) / b; if (d < 0) d = -d; sm += d; n++; if (d > mx) mx = d } }
                   for (o = 0; o < nr; o++) { rm = 0; for (i = 0; i < nc; i++) if (v[2, o, i] > rm) rm = v[2, o, i]
                                              for (i = 0; i < nc; i++) { w = v[2, o, i]; if (w > 0.01 * rm && w > 0) {
                                                  d = (v[1, o, i] - w) / w; if (d < 0) d = -d; el += d; ne++ } } }
                   printf "%.2f %.2f %.2f\n", 100 * sm / n, 100 * mx, 100 * el / ne }' "$1" "$2"
    }
    # name  tree  rmtxop-option  max-colmean  max-colmax  max-elem (percent)
    while read -r name tree opt lmean lmax lel; do
        ref=$REF/bsdf/$tree/${tree}_ttree_klems_$name.mtx
        [ -f "$ref" ] || continue
        [ -f "$T/${tree}_k.xml" ] || bsdf2klems "$REF/bsdf/$tree/${tree}_ttree.xml" > "$T/${tree}_k.xml"
        [ "$opt" = . ] && opt=
        if rmtxop -fa $opt "$T/${tree}_k.xml" > "$T/${tree}_$name.mtx" 2> "$T/kc.err"; then
            set -- $(kcmp "$T/${tree}_$name.mtx" "$ref")
            if awk -v a="$1" -v b="$2" -v c="$3" -v x="$lmean" -v y="$lmax" -v z="$lel" \
                   'BEGIN { exit !(a < x && b < y && c < z) }'; then pass "bsdf2klems_vs_radiance_${tree}_$name"
            else fail "bsdf2klems_vs_radiance_${tree}_$name" "patch sums mean $1 % max $2 %, elements $3 % (limits $lmean $lmax $lel)"; fi
        else
            fail "bsdf2klems_vs_radiance_${tree}_$name" "$(cat "$T/kc.err")"
        fi
    done <<'EOT'
Rf cfs1 -rf 1 1 5
T cfs1 . 3 12 5
T cfs3 . 3 10 10
Rf cfs3 -rf 2 8 10
Rb cfs3 -rb 4 14 15
EOT
    # half basis
    if bsdf2klems -h "$REF/bsdf/cfs3/cfs3_ttree.xml" > "$T/c3h.xml" && checkBSDF "$T/c3h.xml" > "$T/c3h.txt" &&
       grep -q 'Type: Klems_Half' "$T/c3h.txt"; then pass bsdf2klems_half
    else fail bsdf2klems_half "$(head -8 "$T/c3h.txt" 2>/dev/null | tr '\n' ' ')"; fi
else
    skip checkBSDF "no reference folder"
fi

# bad inputs: clear message, non-zero exit, no crash
check_fails checkBSDF_missing 'nonexistent\.xml' checkBSDF "$T/nonexistent.xml"
printf '<?xml version="1.0"?>\n<WindowElement>\n<Optical><Layer>\n<DataDefinition>\n' > "$T/trunc.xml"
check_fails checkBSDF_truncated 'trunc\.xml: line [0-9]+: malformed XML' checkBSDF "$T/trunc.xml"
printf '<WindowElement><Optical><Layer><DataDefinition><IncidentDataStructure>TensorTree4</IncidentDataStructure></DataDefinition><WavelengthData><Wavelength>Visible</Wavelength><WavelengthDataBlock><WavelengthDataDirection>Transmission Back</WavelengthDataDirection><ScatteringData>{ 1 2 3 }</ScatteringData></WavelengthDataBlock></WavelengthData></Layer></Optical></WindowElement>\n' > "$T/count.xml"
check_fails checkBSDF_count 'line 1: <ScatteringData>: tree node at depth 0 has 3 values' checkBSDF "$T/count.xml"
# energy conservation: a one-bin Klems file with T = 0.5 pi > 1 is reported
# on stderr with the file, side and direction; the report itself is printed
printf '<WindowElement><Optical><Layer><DataDefinition><IncidentDataStructure>Columns</IncidentDataStructure><AngleBasis><AngleBasisName>One</AngleBasisName><AngleBasisBlock><Theta>0</Theta><nPhis>1</nPhis><ThetaBounds><LowerTheta>0</LowerTheta><UpperTheta>90</UpperTheta></ThetaBounds></AngleBasisBlock></AngleBasis></DataDefinition><WavelengthData><Wavelength>Visible</Wavelength><WavelengthDataBlock><WavelengthDataDirection>Transmission Front</WavelengthDataDirection><ColumnAngleBasis>One</ColumnAngleBasis><RowAngleBasis>One</RowAngleBasis><ScatteringData>0.5</ScatteringData></WavelengthDataBlock></WavelengthData></Layer></Optical></WindowElement>\n' > "$T/hot.xml"
if checkBSDF "$T/hot.xml" > "$T/hot.txt" 2> "$T/hot.err" && grep -q '^Ext->Int Trans' "$T/hot.txt" &&
   grep -Eq 'hot\.xml: light from the (room|exterior) at theta [0-9.]+ phi [0-9.]+ deg .*T 1\.57[0-9]* \+ R 0\.0000 = 1\.57' "$T/hot.err"; then
    pass checkBSDF_energy
else
    fail checkBSDF_energy "$(head -3 "$T/hot.err" | tr '\n' ' ')"
fi
if have_ref bsdf; then
    checkBSDF "$REF/bsdf/cfs3/cfs3_ttree.xml" > /dev/null 2> "$T/cons.err"
    grep -q 'exceeds' "$T/cons.err" && fail checkBSDF_energy_ok "$(head -2 "$T/cons.err")" || pass checkBSDF_energy_ok
fi
check_fails checkBSDF_noargs 'no BSDF file|usage' checkBSDF
check_fails bsdf2klems_noargs 'exactly one input|usage' bsdf2klems
check_fails bsdf2klems_badn 'n 0: expected 1 to' bsdf2klems -n 0 "$T/count.xml"
check_fails bsdf2klems_bad 'count\.xml' bsdf2klems "$T/count.xml"
