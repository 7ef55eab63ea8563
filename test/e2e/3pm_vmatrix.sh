# Issue 7: the 3PM view matrix at Radiance's recorded sample count against
# Radiance's a3_V_sensors.vmx (../shared/ref/scenes/box, MANIFEST A3):
#   rfluxmtx -faf -y 28 -I+ -ab 8 -ad 32768 -lw 1e-6 - window_rx_pts.rad box_room.rad < sensors.pts
# (about 3 s CPU).
#
# What is achievable (measured, docs/benchmarks/3pm.md): the reference is
# itself one Monte Carlo estimate.  Two more runs of Radiance's own command
# (same input, and sensors in reverse order) differ from a3_V_sensors.vmx by
# 15.3-15.5 % element RMS (elements above 1e-3 of the maximum), 8.3-8.5 %
# worst column sum, 2.2-2.4 % column-sum RMS and 3.3-3.5 % RMS over the
# elements above 1e-1 of the maximum; the reference differs from a
# converged V by 11.0 % RMS.  So the issue's "element RMS < 10 %" and
# "every column sum within 3 %" cannot be met by any V at this sample count,
# Radiance's included.  This test asserts the Radiance-vs-Radiance level
# instead (with ~10 % margin): heliodon's V must be as close to the
# reference as a re-run of Radiance is.
. test/e2e/lib.sh
B=$REF/scenes/box
if ! have_ref scenes/box; then skip all "reference folder $REF/scenes/box not found"; exit 0; fi
command -v rfluxmtx >/dev/null || { fail setup "rfluxmtx not on PATH"; exit 0; }

if ! (cd "$B" && rfluxmtx -n 2 -faf -y 28 -I+ -ab 8 -ad 32768 -lw 1e-6 - window_rx_pts.rad box_room.rad \
        < sensors.pts) > "$T/V.vmx" 2> "$T/V.err"; then
    fail v_run "$(tail -3 "$T/V.err")"; exit 0
fi
rmtxop -fa "$T/V.vmx" > "$T/V.fa" && rmtxop -fa "$B/a3_V_sensors.vmx" > "$T/R.fa" || { fail v_read "rmtxop"; exit 0; }
# element = mean of R, G, B; rows = sensors, columns = Klems bins
elems() { sed '1,/^$/d' "$1" | awk -F'\t' '{ for (i = 1; i <= NF; i++) { n = split($i, c, " "); if (n == 3) print NR, i, (c[1] + c[2] + c[3]) / 3 } }'; }
elems "$T/V.fa" > "$T/v.txt"; elems "$T/R.fa" > "$T/r.txt"
paste -d' ' "$T/v.txt" "$T/r.txt" | awk '
    { a[NR] = $3; b[NR] = $6; col[NR] = $2; if ($1 != $4 || $2 != $5) bad = 1
      ta += $3; tb += $6; ca[$2] += $3; cb[$2] += $6; if ($6 > mx) mx = $6; n = NR }
    END {
      if (bad || n != 28 * 145) { print "layout", n; exit 1 }
      for (c in cb) { d = (ca[c] - cb[c]) / cb[c]; if (d < 0) d = -d; if (d > cmax) cmax = d; cs += d * d; nc++ }
      for (i = 1; i <= n; i++) {
        if (b[i] > 1e-3 * mx) { r = (a[i] - b[i]) / b[i]; s3 += r * r; n3++ }
        if (b[i] > 1e-1 * mx) { r = (a[i] - b[i]) / b[i]; s1 += r * r; n1++ } }
      printf "%.5f %.5f %.5f %.5f %.5f\n", (ta - tb) / tb, cmax, sqrt(cs / nc), sqrt(s3 / n3), sqrt(s1 / n1) }' > "$T/stats.txt" \
    || { fail v_stats "$(cat "$T/stats.txt")"; exit 0; }
read -r tot cmax crms e3 e1 < "$T/stats.txt"
echo "  V -ad 32768 vs a3_V_sensors.vmx: total $tot, column sums max|rel| $cmax rms $crms, element RMS (>1e-3 of max) $e3, (>1e-1 of max) $e1"
t() { n=$1 v=$2 lim=$3 why=$4; if le "$v" "$lim"; then pass "$n"; else fail "$n" "$v > $lim ($why)"; fi; }
abs_tot=$(awk -v t="$tot" 'BEGIN{print t < 0 ? -t : t}')
t v_total "$abs_tot" 0.01 "Radiance re-runs: 0.2 %"
t v_colsum_max "$cmax" 0.095 "Radiance re-runs: 8.3-8.5 %"
t v_colsum_rms "$crms" 0.027 "Radiance re-runs: 2.2-2.4 %"
t v_element_rms "$e3" 0.17 "Radiance re-runs: 15.3-15.5 %; the reference's own noise vs a converged V is 11.0 %"
t v_element_rms_bright "$e1" 0.04 "Radiance re-runs: 3.3-3.5 %"
