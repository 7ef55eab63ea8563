# genBSDF accuracy (issue 22 item 5): clear double glazing (two Radiance
# glass panes, the shared reference geometry ../shared/ref/bsdf/geom/glazing.rad
# written out below) at Radiance's default -c 2000, Transmission Front,
# against the converged Radiance genBSDF -c 20000 in test/data/genbsdf
# (commands in its MANIFEST.md).  The bar: heliodon's error is no larger
# than Radiance's own genBSDF -c 2000 against the same reference, for each
# of klems_err.awk's figures (mean and largest per-patch error of the
# directional-hemispherical transmittance, largest below 75 degrees and in
# the grazing ring separately, mean element-wise error).  Radiance's figures
# come from its -c 2000 run in the reference set when HELIODON_REF has it,
# else from the MANIFEST (the same run).
. test/e2e/lib.sh

D=test/data/genbsdf
cat > "$T/glazing.rad" <<'RAD'
void glass clear_glass 0 0 3 0.96 0.96 0.96
clear_glass polygon pane_ext 0 0 12  -1000 -1000 -18  1000 -1000 -18  1000 1000 -18  -1000 1000 -18
clear_glass polygon pane_int 0 0 12  -1000 -1000 -2  1000 -1000 -2  1000 1000 -2  -1000 1000 -2
RAD
gunzip -c "$D/glazing_c20000.xml.gz" > "$T/ref.xml" && rmtxop -fa "$T/ref.xml" > "$T/ref.mtx" 2> "$T/err" ||
    fail glazing_reference "$(head -3 "$T/err" | tr '\n' ' ')"
# Radiance genBSDF -c 2000 against the converged reference (MANIFEST.md)
rad="0.021 0.086 0.353 0.021"
if [ -f "$REF/bsdf/glazing/glazing_klems_T.mtx" ]; then
    rad=$(awk -f "$D/klems_err.awk" "$REF/bsdf/glazing/glazing_klems_T.mtx" "$T/ref.mtx")
fi
if genBSDF -n 1 -c 2000 +f -b -geom millimeter -dim -50 50 -50 50 -20 0 "$T/glazing.rad" > "$T/h.xml" 2> "$T/err" &&
   rmtxop -fa "$T/h.xml" > "$T/h.mtx" 2>> "$T/err" &&
   ours=$(awk -f "$D/klems_err.awk" "$T/h.mtx" "$T/ref.mtx"); then
    echo "  glazing -c 2000, error % (mean, max < 75 deg, max grazing, element-wise): heliodon $ours, Radiance $rad"
    set -- $ours $rad
    for k in 1 2 3 4; do
        eval "a=\${$k} b=\${$((k + 4))}"
        name=$(echo "mean inner grazing elem" | cut -d' ' -f$k)
        if le "$a" "$b"; then pass "glazing_c2000_$name"
        else fail "glazing_c2000_$name" "heliodon $a % > Radiance $b %"; fi
    done
else
    fail glazing_c2000 "$(head -3 "$T/err" | tr '\n' ' ')"
fi
