#!/bin/bash
# compare_html.sh TITLE timings.txt VIEW.csv... > index.html: the methods of a run side by side (methods.mk,
# "make compare"): per glare view the DGP histograms (bins of 0.05) and cumulative curves (fraction
# of hours with DGP <= x) of every method present, with their 95th percentiles, the pairwise
# agreement (compare.sh) and the hours of largest disagreement.
set -eu
title=$1; timings=$2; shift 2
esc() { sed -e 's/&/\&amp;/g' -e 's/</\&lt;/g' -e 's/>/\&gt;/g'; }
here=$(dirname "$0")
echo "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>$(echo "$title" | esc): methods</title>"
echo "<style>body{font-family:sans-serif;max-width:64em;margin:auto}table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px;text-align:right}</style></head><body>"
echo "<h1>$(echo "$title" | esc): the methods side by side</h1>"
echo "<p>PM-CBDM (pm), the plain three-phase method with the sun (3pm) and imageless DGP (imageless), hour by hour over the hours each has.</p>"
# wall time of each method: the sum of its stages in the run's timings (pipeline stage.sh); the view
# matrices (rfluxmtx_V_) count for the 3PM
if [ -s "$timings" ]; then
    echo "<h2>Wall time per method</h2><table><tr><th>method</th><th>stages</th><th>wall time (s)</th></tr>"
    awk '$1 ~ /^report_/ {next} {m = $1 ~ /^(3pm_|rfluxmtx_V_)/ ? "3pm" : $1 ~ /^imageless_/ ? "imageless" : "pm"; t[m] += $2; n[m]++}
        END {split("pm 3pm imageless", o, " "); for (i = 1; i <= 3; i++) if (n[o[i]]) printf "<tr><td>%s</td><td>%d</td><td>%.1f</td></tr>\n", o[i], n[o[i]], t[o[i]]}' "$timings"
    echo "</table>"
fi
for csv in "$@"; do
    v=$(basename "$csv" .csv)
    echo "<h2>View $v</h2><pre>"; "$here/compare.sh" "$csv" | esc; echo "</pre>"
    # histogram (bars side by side) and cumulative curves, one SVG each
    awk -F, -v view="$v" '
    function p95(col,   n, i, k, f, x, j, t) { n = 0; for (i = 2; i <= N; i++) if (V[i, col] != "") x[++n] = V[i, col] + 0;
        for (i = 2; i <= n; i++) { t = x[i]; j = i - 1; while (j > 0 && x[j] > t) { x[j + 1] = x[j]; j-- } x[j + 1] = t }
        if (!n) return -1; k = 0.95 * (n - 1) + 1; i = int(k); f = k - i; return i < n ? x[i] + f * (x[i + 1] - x[i]) : x[n] }
    NR == 1 { for (j = 5; j <= 7; j++) name[j] = $j; next }
    { N = NR; for (j = 5; j <= 7; j++) V[NR, j] = $j }
    END {
        col[5] = "#d62728"; col[6] = "#1f77b4"; col[7] = "#2ca02c"; nb = 20
        for (j = 5; j <= 7; j++) { cnt[j] = 0; for (b = 0; b < nb; b++) h[j, b] = 0
            for (i = 2; i <= N; i++) if (V[i, j] != "") { b = int(V[i, j] * nb); if (b >= nb) b = nb - 1; if (b < 0) b = 0; h[j, b]++; cnt[j]++ } }
        hmax = 1; for (j = 5; j <= 7; j++) for (b = 0; b < nb; b++) if (cnt[j] && h[j, b] / cnt[j] > hmax / 100) hmax = 100 * h[j, b] / cnt[j]
        W = 520; H = 240; L = 50; B = 200; pw = W - L - 20; ph = B - 20
        printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-size=\"11\">\n", W, H
        printf "<text x=\"%d\" y=\"12\">DGP histogram, view %s (%% of the hours)</text>\n", L, view
        printf "<line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"black\"/>\n", L, B, L + pw, B
        for (t = 0; t <= 10; t += 2) printf "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%.1f</text>\n", L + pw * t / 10, B + 14, t / 10
        printf "<text x=\"5\" y=\"%d\">%.0f%%</text><text x=\"5\" y=\"%d\">0</text>\n", B - ph + 4, hmax, B
        k = 0; for (j = 5; j <= 7; j++) if (cnt[j]) {
            for (b = 0; b < nb; b++) { y = ph * (100 * h[j, b] / cnt[j]) / hmax
                printf "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"%s\"/>\n", L + pw * b / nb + k * pw / nb / 3, B - y, pw / nb / 3, y, col[j] }
            printf "<text x=\"%d\" y=\"%d\" fill=\"%s\">%s (%d h)</text>\n", L + pw - 110, 30 + 14 * k, col[j], name[j], cnt[j]; k++ }
        print "</svg>"
        printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-size=\"11\">\n", W, H
        printf "<text x=\"%d\" y=\"12\">cumulative: fraction of hours with DGP &lt;= x; dashed: 95th percentiles</text>\n", L
        printf "<line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"black\"/><line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"black\"/>\n", L, B, L + pw, B, L, B, L, B - ph
        for (t = 0; t <= 10; t += 2) printf "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%.1f</text>\n", L + pw * t / 10, B + 14, t / 10
        printf "<text x=\"20\" y=\"%d\">1</text><text x=\"20\" y=\"%d\">0</text>\n", B - ph + 4, B
        k = 0; for (j = 5; j <= 7; j++) if (cnt[j]) { c = 0; pts = sprintf("%d,%d", L, B)
            for (b = 0; b < nb; b++) { c += h[j, b]; pts = pts sprintf(" %.1f,%.1f", L + pw * (b + 1) / nb, B - ph * c / cnt[j]) }
            printf "<polyline points=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"2\"/>\n", pts, col[j]
            p = p95(j); printf "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"%s\" stroke-dasharray=\"4,3\"/>\n", L + pw * p, B, L + pw * p, B - ph, col[j]
            printf "<text x=\"%d\" y=\"%d\" fill=\"%s\">%s p95 %.3f</text>\n", L + 10, 30 + 14 * k, col[j], name[j], p; k++ }
        print "</svg>" }' "$csv"
    # the hours of largest disagreement between the image-based methods and each other method
    echo "<p>Hours of largest |dDGP| (up to 10 per pair):</p><table><tr><th>pair</th><th>record</th><th>date</th><th>hour</th><th>DGP a</th><th>DGP b</th><th>a &minus; b</th></tr>"
    for p in "5 6" "5 7" "6 7"; do
        set -- $p
        awk -F, -v a=$1 -v b=$2 'NR == 1 {na = $a; nb = $b; next} $a != "" && $b != "" {d = $a - $b; printf "%.6f,%s vs %s,%s,%s/%s,%s,%s,%s,%+.4f\n", (d < 0 ? -d : d), na, nb, $1, $2, $3, $4, $a, $b, d}' "$csv" |
            sort -t, -k1,1gr | head -10 | awk -F, '{printf "<tr><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n", $2, $3, $4, $5, $6, $7, $8}'
    done
    echo "</table><p>Hour by hour: <a href=\"$v.csv\">$v.csv</a>.</p>"
done
echo "</body></html>"
