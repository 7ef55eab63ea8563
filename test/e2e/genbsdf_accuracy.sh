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
# else from the MANIFEST (the same run).  The same for the CFS3 prism film
# (../shared/ref/bsdf/geom, run only when HELIODON_REF has it).
. test/e2e/lib.sh

# bar SYSTEM "OURS" "RADIANCE": each of the four figures no larger
bar() {
    echo "  $1 -c 2000, error % (mean, max < 75 deg, max grazing, element-wise): heliodon $2, Radiance $3"
    set -- "$1" $2 $3
    sys=$1; shift
    for k in 1 2 3 4; do
        eval "a=\${$k} b=\${$((k + 4))}"
        name=$(echo "mean inner grazing elem" | cut -d' ' -f$k)
        if le "$a" "$b"; then pass "${sys}_c2000_$name"
        else fail "${sys}_c2000_$name" "heliodon $a % > Radiance $b %"; fi
    done
}

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
    bar glazing "$ours" "$rad"
else
    fail glazing_c2000 "$(head -3 "$T/err" | tr '\n' ' ')"
fi

G=$REF/bsdf/geom
if [ -f "$G/cfs3.rad" ] && [ -f "$G/prism_glass.mat" ]; then
    gunzip -c "$D/cfs3_c20000.xml.gz" > "$T/ref3.xml" && rmtxop -fa "$T/ref3.xml" > "$T/ref3.mtx" 2> "$T/err" ||
        fail cfs3_reference "$(head -3 "$T/err" | tr '\n' ' ')"
    rad="0.425 2.773 3.268 7.424"
    if [ -f "$REF/bsdf/cfs3/cfs3_klems_T.mtx" ]; then
        rad=$(awk -f "$D/klems_err.awk" "$REF/bsdf/cfs3/cfs3_klems_T.mtx" "$T/ref3.mtx")
    fi
    if genBSDF -n 2 -c 2000 +f -b -geom millimeter -dim -50 50 -50 50 -4.62 0 "$G/prism_glass.mat" "$G/cfs3.rad" \
           > "$T/h3.xml" 2> "$T/err" &&
       rmtxop -fa "$T/h3.xml" > "$T/h3.mtx" 2>> "$T/err" &&
       ours=$(awk -f "$D/klems_err.awk" "$T/h3.mtx" "$T/ref3.mtx"); then
        bar cfs3 "$ours" "$rad"
    else
        fail cfs3_c2000 "$(head -3 "$T/err" | tr '\n' ' ')"
    fi
else
    skip cfs3_c2000 "no $G/cfs3.rad"
fi
