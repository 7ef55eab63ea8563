# falsecolor's tabulated palettes "def" and "tbo" against Radiance 6.1's
# colours measured on a ramp (test/data/falsecolor/samples_*.txt, see
# MANIFEST.md there): the same probe run with heliodon's falsecolor reads
# each channel to about 1e-7 (three RGBE pictures per value), at the 1025
# values v = k/1024; heliodon evaluates the same tables with the same
# arithmetic, so every sample must agree to the printed digits (1e-9).
. test/e2e/lib.sh
D=$(pwd)/test/data/falsecolor
mkdir -p "$T/probe"
if ! ( cd "$T/probe" && bash "$D/probe.sh" ) 2> "$T/probe.err"; then
    fail probe "$(head -3 "$T/probe.err" | tr '\n' ' ')"; exit 0
fi
for pal in def tbo; do
    tol=1e-9
    r=$(paste -d' ' "$T/probe/samples_$pal.txt" "$D/samples_$pal.txt" |
        awk -v tol=$tol '{ if ($1 != $5) { print "v " $1 " vs " $5; bad = 1; exit }
                           for (i = 2; i <= 4; i++) { d = $i - $(i + 4); if (d < 0) d = -d; if (d > m) { m = d; at = $1 } } }
                         END { if (!bad) { printf "%d samples, max |diff| %.2e at v=%s", NR, m, at; exit !(NR == 1025 && m <= tol) } exit 1 }') &&
        pass "palette_$pal" || fail "palette_$pal" "$r"
    echo "palette $pal: $r"
done
