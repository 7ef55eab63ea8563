#!/bin/bash
# compare_html.sh TITLE timings.txt VIEW.csv... > index.html: the methods of a run side by side (methods.mk,
# "make compare"): per glare view the DGP histograms (bins of 0.05) and cumulative curves (fraction
# of hours with DGP <= x) of every method present, with their 95th percentiles, the same for DGI
# (VIEW_dgi.csv beside VIEW.csv, bins of 2 up to 40; imageless has no DGI), the heat map (day of the
# year x hour) of the DGP difference PM - 5PM, the pairwise agreement (compare.sh) and the hours of
# largest disagreement.
set -eu
title=$1; timings=$2; shift 2
esc() { sed -e 's/&/\&amp;/g' -e 's/</\&lt;/g' -e 's/>/\&gt;/g'; }
here=$(dirname "$0")
echo "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>$(echo "$title" | esc): methods</title>"
echo "<style>body{font-family:sans-serif;max-width:64em;margin:auto}table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px;text-align:right}</style></head><body>"
echo "<h1>$(echo "$title" | esc): the methods side by side</h1>"
echo "<p>PM-CBDM (pm), the plain three-phase method with the sun (3pm), imageless DGP (imageless) and the five-phase method (5pm), hour by hour over the hours each has.</p>"
# wall time of each method: the sum of its stages in the run's timings (pipeline stage.sh); the view
# matrices (rfluxmtx_V_) count for the 3PM, the 3PM's stages for the 5PM too; the backward references
# of "make reference" (reference_, reference1_) are not a method's
walltimes() {
    [ -s "$timings" ] || return 0
    awk '$1 ~ /^(report_|reference)/ {next} {m = $1 ~ /^(3pm_|rfluxmtx_V_)/ ? "3pm" : $1 ~ /^imageless_/ ? "imageless" : $1 ~ /^5pm_/ ? "5pm" : "pm"; t[m] += $2; n[m]++}
        END {if (n["5pm"]) {t["5pm"] += t["3pm"]; n["5pm"] += n["3pm"]}
             split("pm 3pm imageless 5pm", o, " "); for (i = 1; i <= 4; i++) if (n[o[i]]) printf "%s %d %.1f\n", o[i], n[o[i]], t[o[i]]}' "$timings"
}
if [ -s "$timings" ]; then
    echo "<h2>Wall time per method</h2><table><tr><th>method</th><th>stages</th><th>wall time (s)</th></tr>"
    walltimes | awk '{printf "<tr><td>%s</td><td>%d</td><td>%.1f</td></tr>\n", $1, $2, $3}'
    echo "</table><p>The 5PM's time includes the 3PM stages it reuses (V, D, T).</p>"
fi
# charts CSV QUANTITY MAX: histogram (bars side by side, 20 bins of MAX/20) and cumulative curves of
# the columns 5-8 of CSV, one SVG each, with the 95th percentiles
charts() {
    awk -F, -v view="$v" -v q="$2" -v hi="$3" '
    function p95(col,   n, i, k, f, x, j, t) { n = 0; for (i = 2; i <= N; i++) if (V[i, col] != "") x[++n] = V[i, col] + 0;
        for (i = 2; i <= n; i++) { t = x[i]; j = i - 1; while (j > 0 && x[j] > t) { x[j + 1] = x[j]; j-- } x[j + 1] = t }
        if (!n) return -1; k = 0.95 * (n - 1) + 1; i = int(k); f = k - i; return i < n ? x[i] + f * (x[i + 1] - x[i]) : x[n] }
    NR == 1 { for (j = 5; j <= 8; j++) name[j] = $j; next }
    { N = NR; for (j = 5; j <= 8; j++) V[NR, j] = $j }
    END {
        col[5] = "#d62728"; col[6] = "#1f77b4"; col[7] = "#2ca02c"; col[8] = "#9467bd"; nb = 20
        for (j = 5; j <= 8; j++) { cnt[j] = 0; for (b = 0; b < nb; b++) h[j, b] = 0
            for (i = 2; i <= N; i++) if (V[i, j] != "") { b = int(V[i, j] / hi * nb); if (b >= nb) b = nb - 1; if (b < 0) b = 0; h[j, b]++; cnt[j]++ } }
        hmax = 1; for (j = 5; j <= 8; j++) for (b = 0; b < nb; b++) if (cnt[j] && h[j, b] / cnt[j] > hmax / 100) hmax = 100 * h[j, b] / cnt[j]
        W = 520; H = 240; L = 50; B = 200; pw = W - L - 20; ph = B - 20
        printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-size=\"11\">\n", W, H
        printf "<text x=\"%d\" y=\"12\">%s histogram, view %s (%% of the hours)</text>\n", L, q, view
        printf "<line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"black\"/>\n", L, B, L + pw, B
        for (t = 0; t <= 10; t += 2) printf "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%g</text>\n", L + pw * t / 10, B + 14, hi * t / 10
        printf "<text x=\"5\" y=\"%d\">%.0f%%</text><text x=\"5\" y=\"%d\">0</text>\n", B - ph + 4, hmax, B
        k = 0; for (j = 5; j <= 8; j++) if (cnt[j]) {
            for (b = 0; b < nb; b++) { y = ph * (100 * h[j, b] / cnt[j]) / hmax
                printf "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"%s\"/>\n", L + pw * b / nb + k * pw / nb / 4, B - y, pw / nb / 4, y, col[j] }
            printf "<text x=\"%d\" y=\"%d\" fill=\"%s\">%s (%d h)</text>\n", L + pw - 110, 30 + 14 * k, col[j], name[j], cnt[j]; k++ }
        print "</svg>"
        printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-size=\"11\">\n", W, H
        printf "<text x=\"%d\" y=\"12\">cumulative: fraction of hours with %s &lt;= x; dashed: 95th percentiles</text>\n", L, q
        printf "<line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"black\"/><line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"black\"/>\n", L, B, L + pw, B, L, B, L, B - ph
        for (t = 0; t <= 10; t += 2) printf "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%g</text>\n", L + pw * t / 10, B + 14, hi * t / 10
        printf "<text x=\"20\" y=\"%d\">1</text><text x=\"20\" y=\"%d\">0</text>\n", B - ph + 4, B
        k = 0; for (j = 5; j <= 8; j++) if (cnt[j]) { c = 0; pts = sprintf("%d,%d", L, B)
            for (b = 0; b < nb; b++) { c += h[j, b]; pts = pts sprintf(" %.1f,%.1f", L + pw * (b + 1) / nb, B - ph * c / cnt[j]) }
            printf "<polyline points=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"2\"/>\n", pts, col[j]
            p = p95(j); printf "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"%s\" stroke-dasharray=\"4,3\"/>\n", L + pw * p / hi, B, L + pw * p / hi, B - ph, col[j]
            printf "<text x=\"%d\" y=\"%d\" fill=\"%s\">%s p95 %.4g</text>\n", L + 10, 30 + 14 * k, col[j], name[j], p; k++ }
        print "</svg>" }' "$1"
}
# heatmap CSV: day of the year (x) by hour (y) of the DGP difference pm - 5pm (columns 5 and 8), red
# where PM-CBDM is higher, blue where the 5PM is, full colour at |dDGP| >= 0.2
heatmap() {
    awk -F, -v view="$v" '
    BEGIN { split("31 28 31 30 31 30 31 31 30 31 30 31", ml, " "); c0[1] = 0; for (m = 2; m <= 12; m++) c0[m] = c0[m - 1] + ml[m - 1] }
    NR > 1 && $5 != "" && $8 != "" { n++; d[n] = $5 - $8; doy[n] = c0[$2 + 0] + $3; hr[n] = $4 }
    END { if (!n) exit
        W = 2 * 365 + 80; H = 8 * 24 + 50; L = 40; T = 20
        printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-size=\"11\">\n", W, H
        printf "<text x=\"%d\" y=\"12\">DGP difference PM - 5PM, view %s: day of the year x hour (%d hours; red: PM higher, blue: 5PM higher, full at 0.2)</text>\n", L, view, n
        printf "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"#eee\"/>\n", L, T, 2 * 365, 8 * 24
        for (i = 1; i <= n; i++) { a = d[i] / 0.2; if (a > 1) a = 1; if (a < -1) a = -1
            r = a > 0 ? 255 : int(255 * (1 + a)); b = a < 0 ? 255 : int(255 * (1 - a)); g = int(255 * (1 - (a < 0 ? -a : a)))
            printf "<rect x=\"%d\" y=\"%d\" width=\"2\" height=\"8\" fill=\"rgb(%d,%d,%d)\"><title>day %d, %.2f h: %+.4f</title></rect>\n", L + 2 * (doy[i] - 1), T + 8 * int(hr[i]), r, g, b, doy[i], hr[i], d[i] }
        for (h = 0; h <= 24; h += 6) printf "<text x=\"5\" y=\"%d\">%d h</text>\n", T + 8 * h + 4, h
        for (m = 1; m <= 12; m++) printf "<text x=\"%d\" y=\"%d\">%d</text>\n", L + 2 * c0[m], T + 8 * 24 + 14, m
        print "</svg>" }' "$1"
}
# timeerr table.csv: wall time (x, log scale, the run's timings) of each method against its mean error
# over the reference hours (y: mean |dE_v| in % of the reference's, left; mean |dDGP|, right), one point
# per method
timeerr() {
    walltimes | awk -F, -v view="$v" 'FILENAME == "-" {split($0, w, " "); t[w[1]] = w[3]; next}
        FNR > 1 && $5 == "ref" {e[$1] = $6; g[$1] = $10; nh++}
        FNR > 1 && $5 != "ref" && $5 != "ref1" {row[++n] = $0}
        END {
            for (i = 1; i <= n; i++) {split(row[i], a, ","); m = a[5]; if (!(a[1] in e) || e[a[1]] <= 0) continue
                de = a[6] / e[a[1]] - 1; dg = a[10] - g[a[1]]; se[m] += de < 0 ? -de : de; sg[m] += dg < 0 ? -dg : dg; k[m]++ }
            col["pm"] = "#d62728"; col["3pm"] = "#1f77b4"; col["imageless"] = "#2ca02c"; col["5pm"] = "#9467bd"
            tmin = 1e30; tmax = 0; for (m in k) if (m in t) {if (t[m] < tmin) tmin = t[m]; if (t[m] > tmax) tmax = t[m]
                if (100 * se[m] / k[m] > ye) ye = 100 * se[m] / k[m]; if (sg[m] / k[m] > yg) yg = sg[m] / k[m]}
            if (tmax <= 0) exit
            if (tmin < 0.1) tmin = 0.1; lo = int(log(tmin) / log(10) + 10) - 10; hi = int(log(tmax) / log(10) + 10) - 9; if (hi <= lo) hi = lo + 1
            ye = ye > 0 ? ye * 1.15 : 1; yg = yg > 0 ? yg * 1.15 : 0.01
            W = 560; H = 260; printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-size=\"11\">\n", W, H
            printf "<text x=\"10\" y=\"12\">view %s: wall time of each method (s, log) against its mean error over the %d reference hours</text>\n", view, nh
            for (p = 0; p < 2; p++) { L = 50 + p * 280; B = 220; pw = 220; ph = 180; ym = p ? yg : ye
                printf "<line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"black\"/><line x1=\"%d\" y1=\"%d\" x2=\"%d\" y2=\"%d\" stroke=\"black\"/>\n", L, B, L + pw, B, L, B, L, B - ph
                printf "<text x=\"%d\" y=\"%d\">%s</text>\n", L, B - ph - 6, p ? "mean |dDGP|" : "mean |dE_v| (%)"
                printf "<text x=\"%d\" y=\"%d\" text-anchor=\"end\">%.3g</text><text x=\"%d\" y=\"%d\" text-anchor=\"end\">0</text>\n", L - 3, B - ph + 4, ym, L - 3, B
                for (d = lo; d <= hi; d++) printf "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%g</text>\n", L + pw * (d - lo) / (hi - lo), B + 14, 10 ^ d
                printf "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">wall time (s)</text>\n", L + pw / 2, B + 28
                for (m in k) if (m in t) { x = L + pw * (log(t[m] < 0.1 ? 0.1 : t[m]) / log(10) - lo) / (hi - lo); y = B - ph * (p ? sg[m] / k[m] : 100 * se[m] / k[m]) / ym
                    printf "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"%s\"><title>%s: %.1f s, mean |dE_v| %.1f %%, mean |dDGP| %.4f</title></circle>\n", x, y, col[m], m, t[m], 100 * se[m] / k[m], sg[m] / k[m]
                    printf "<text x=\"%.1f\" y=\"%.1f\" fill=\"%s\">%s</text>\n", x + 6, y + 4, col[m], m } }
            print "</svg>" }' - "$1"
}
for csv in "$@"; do
    v=$(basename "$csv" .csv)
    echo "<h2>View $v</h2><pre>"; "$here/compare.sh" "$csv" | esc; echo "</pre>"
    charts "$csv" DGP 1
    dgi=${csv%.csv}_dgi.csv
    if [ -s "$dgi" ]; then charts "$dgi" DGI 40; fi
    heatmap "$csv"
    # the hours of largest disagreement between the image-based methods and each other method
    echo "<p>Hours of largest |dDGP| (up to 10 per pair):</p><table><tr><th>pair</th><th>record</th><th>date</th><th>hour</th><th>DGP a</th><th>DGP b</th><th>a &minus; b</th></tr>"
    for p in "5 6" "5 7" "5 8" "6 7" "6 8" "7 8"; do
        set -- $p
        awk -F, -v a=$1 -v b=$2 'NR == 1 {na = $a; nb = $b; next} $a != "" && $b != "" {d = $a - $b; printf "%.6f,%s vs %s,%s,%s/%s,%s,%s,%s,%+.4f\n", (d < 0 ? -d : d), na, nb, $1, $2, $3, $4, $a, $b, d}' "$csv" |
            sort -t, -k1,1gr | head -10 | awk -F, '{printf "<tr><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td></tr>\n", $2, $3, $4, $5, $6, $7, $8}'
    done
    echo "</table><p>Hour by hour: <a href=\"$v.csv\">$v.csv</a>.</p>"
    ref=${csv%.csv}_ref
    if [ -s "$ref/table.csv" ] && [ -s "$ref/table.html" ]; then
        cat "$ref/table.html"
        timeerr "$ref/table.csv" > "${csv%.csv}_time_error.svg.tmp" && mv -f "${csv%.csv}_time_error.svg.tmp" "${csv%.csv}_time_error.svg"
        echo "<p><img src=\"${v}_time_error.svg\" alt=\"wall time against error, view $v\"></p>"
    fi
done
echo "</body></html>"
