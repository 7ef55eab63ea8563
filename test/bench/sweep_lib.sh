#!/usr/bin/env bash
# Helpers sourced by test/bench/sweep_*.sh (running this file alone does
# nothing).  Timing, error measures through hdcompare, SVG charts in awk.
if [ "${BASH_SOURCE[0]}" = "$0" ]; then exit 0; fi
set -euo pipefail
BUILD=${BUILD:-build}
REF=${HELIODON_REF:-../shared/ref}
BOX=$REF/scenes/box
ROOT=$(pwd)
BIN=$(cd "$BUILD/bin" && pwd)
DOCS=$ROOT/docs/benchmarks
RB=${RADIANCE_BIN:-}
if [ -n "$RB" ] && [ ! -x "$RB/rtrace" ]; then echo "RADIANCE_BIN=$RB has no rtrace; Radiance curves left out"; RB=; fi
if [ -n "$RB" ]; then export RAYPATH=".:$(cd "$RB/../lib" 2>/dev/null && pwd || echo /usr/local/lib/ray)"; fi
# wall-clock seconds of a command (its stdout/stderr as redirected by the caller)
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN{printf "%.3f", b-a}'; }
# value of key in hdcompare output
cmpval() { awk -v k="$2" '$1==k{print $2}' "$1"; }
header() { echo "date: $(date -u '+%Y-%m-%d %H:%M') UTC, machine: $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"; }
# svgchart TSV SVG TITLE XLABEL YLABEL : TSV lines "series<TAB>x<TAB>y";
# log-log axes, one polyline + markers per series, legend.
svgchart() {
    awk -F'\t' -v title="$3" -v xl="$4" -v yl="$5" '
    BEGIN { ns = 0 }   # series ids from 0 (an unset ns made the first one "" and dropped it)
    function lg(v) { return log(v)/log(10) }
    NF >= 3 && $2 > 0 && $3 > 0 {
        s = $1; if (!(s in id)) { id[s] = ns; name[ns++] = s }
        k = id[s]; n[k]++; X[k, n[k]] = lg($2); Y[k, n[k]] = lg($3)
        if (first++ == 0) { x0 = x1 = lg($2); y0 = y1 = lg($3) }
        if (lg($2) < x0) x0 = lg($2); if (lg($2) > x1) x1 = lg($2)
        if (lg($3) < y0) y0 = lg($3); if (lg($3) > y1) y1 = lg($3)
    }
    END {
        W = 640; H = 420; L = 70; R = 190; T = 40; B = 50
        x0 = int(x0 - (x0 < 0 ? 1 : 0)); x1 = int(x1) + 1; if (x1 <= x0) x1 = x0 + 1
        y0 = int(y0 - (y0 < 0 ? 1 : 0)); y1 = int(y1) + 1; if (y1 <= y0) y1 = y0 + 1
        printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-family=\"sans-serif\" font-size=\"12\">\n", W, H
        printf "<rect width=\"%d\" height=\"%d\" fill=\"white\"/>\n", W, H
        printf "<text x=\"%d\" y=\"22\" font-size=\"14\">%s</text>\n", L, title
        pw = W - L - R; ph = H - T - B
        for (d = x0; d <= x1; d++) { px = L + (d - x0) / (x1 - x0) * pw
            printf "<line x1=\"%.1f\" y1=\"%d\" x2=\"%.1f\" y2=\"%d\" stroke=\"#ddd\"/>\n", px, T, px, T + ph
            printf "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">1e%d</text>\n", px, T + ph + 16, d }
        for (d = y0; d <= y1; d++) { py = T + ph - (d - y0) / (y1 - y0) * ph
            printf "<line x1=\"%d\" y1=\"%.1f\" x2=\"%d\" y2=\"%.1f\" stroke=\"#ddd\"/>\n", L, py, L + pw, py
            printf "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">1e%d</text>\n", L - 4, py + 4, d }
        printf "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"black\"/>\n", L, T, pw, ph
        printf "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">%s</text>\n", L + pw / 2, H - 10, xl
        printf "<text x=\"14\" y=\"%d\" transform=\"rotate(-90 14 %d)\" text-anchor=\"middle\">%s</text>\n", T + ph / 2, T + ph / 2, yl
        split("#1f77b4 #d62728 #2ca02c #ff7f0e #9467bd #8c564b #e377c2 #7f7f7f", col, " ")
        for (k = 0; k < ns; k++) { c = col[k % 8 + 1]; pts = ""
            for (i = 1; i <= n[k]; i++) {
                px = L + (X[k, i] - x0) / (x1 - x0) * pw; py = T + ph - (Y[k, i] - y0) / (y1 - y0) * ph
                pts = pts sprintf("%.1f,%.1f ", px, py)
                printf "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3.5\" fill=\"%s\"/>\n", px, py, c }
            printf "<polyline points=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\"/>\n", pts, c
            printf "<rect x=\"%d\" y=\"%d\" width=\"12\" height=\"12\" fill=\"%s\"/>\n", W - R + 10, T + 6 + 18 * k, c
            printf "<text x=\"%d\" y=\"%d\">%s</text>\n", W - R + 28, T + 16 + 18 * k, name[k] }
        print "</svg>"
    }' "$1" > "$2.tmp" && mv "$2.tmp" "$2"
}
# slopes TSV : least-squares slope of log(error) vs log(x) per series (the
# convergence slope; -0.5 = the 1/sqrt(N) law when x is proportional to N)
slopes() {
    awk -F'\t' '$2 > 0 && $3 > 0 { s=$1; x=log($2); y=log($3); n[s]++; sx[s]+=x; sy[s]+=y; sxx[s]+=x*x; sxy[s]+=x*y }
        END { for (s in n) if (n[s] >= 3) { d = n[s]*sxx[s] - sx[s]*sx[s]
              if (d > 0) printf "convergence slope %-28s %6.3f (%d points)\n", s, (n[s]*sxy[s] - sx[s]*sy[s]) / d, n[s] } }' "$1"
}
# tmem OUTFILE CMD... : run CMD with stdout to OUTFILE (stdin inherited);
# sets TM_WALL (s) and TM_RSS (peak resident MB)
tmem() {
    local out=$1; shift
    /usr/bin/time -f "%e %M" -o "$W/tmem.txt" "$@" > "$out"
    read -r TM_WALL TM_RSS < "$W/tmem.txt"
    TM_RSS=$(awk -v k="$TM_RSS" 'BEGIN{printf "%.0f", k/1024}')
}
# rss CMD... : run CMD (stdio as redirected by the caller) recording its peak
# resident set in $W/rss.txt; rssmb prints it in MB
rss() { /usr/bin/time -f %M -o "$W/rss.txt" "$@"; }
rssmb() { awk '{v=$1} END{printf "%.0f", v/1024}' "$W/rss.txt"; }
