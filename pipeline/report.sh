#!/bin/bash
# report.sh OUT REPORTDIR TITLE "views" "glare views" "sensors" SENSORDIR params.txt > index.html
# The run's front page: one section per view and per sensor grid (heliodon.mk).
set -eu
out=$1 rep=$2 title=$3 views=$4 glare=$5 sensors=$6 sdir=$7 params=$8
esc() { sed -e 's/&/\&amp;/g' -e 's/</\&lt;/g' -e 's/>/\&gt;/g'; }
echo "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>$(echo "$title" | esc)</title>"
echo "<style>body{font-family:sans-serif;max-width:60em;margin:auto}table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px;text-align:right}</style></head><body>"
echo "<h1>$(echo "$title" | esc)</h1>"
echo "<h2>Run</h2><pre>"; esc < "$params"; echo "</pre>"
for v in $views; do
    echo "<h2 id=\"view-$v\">View $v</h2>"
    if [[ " $glare " == *" $v "* ]]; then
        echo "<p>Annual glare: <a href=\"$v/index.html\">full report of view $v</a>; CSV <code>$v/annual.csv</code>.</p><pre>"
        grep -E '^(hours|DGP_p95|DGI_p95|shade_closed|open_only_DGP_p95|DGP_class|dgp)' "$out/$v/summary.txt" 2>/dev/null | esc || true
        echo "</pre>"
        for f in "$rep/$v"/*.svg; do [ -e "$f" ] && echo "<img src=\"$v/$(basename "$f")\" style=\"max-width:48%\">"; done
    else
        echo "<p>Images only (not a 180&deg; fisheye view: no glare).  Selected hours (mean luminance, cd/m&sup2;):</p><ul>"
        mkdir -p "$rep/$v"
        for img in "$out/$v"/selected/h*.hdr; do
            [ -e "$img" ] || continue
            cp "$img" "$rep/$v/"
            r=$(basename "$img" .hdr); r=$((10#${r#h}))
            ml=$(awk -v r="$r" '$1 == r {print $2 "/" $3 " " $4 " h: " $12}' "$out/$v/hours.log")
            echo "<li><a href=\"$v/$(basename "$img")\">record $r</a> ($ml)</li>"
        done
        echo "</ul>"
    fi
done
for s in $sensors; do
    d=$sdir/$s
    echo "<h2 id=\"sensors-$s\">Sensor grid $s</h2><pre>"; esc < "$d/metrics_summary.txt"; echo "</pre>"
    cp "$d/metrics.csv" "$rep/metrics_$s.csv"; cp "$d/illuminance.csv" "$rep/illuminance_$s.csv"
    echo "<p>Per point: <a href=\"metrics_$s.csv\">metrics_$s.csv</a>; hourly illuminance: <a href=\"illuminance_$s.csv\">illuminance_$s.csv</a>.</p>"
    echo "<table><tr><th>point</th><th>x</th><th>y</th><th>z</th><th>DA</th><th>UDI&lt;</th><th>UDI-s</th><th>UDI-a</th><th>UDI&gt;</th><th>ASE h</th></tr>"
    awk -F, 'NR > 1 && NR <= 201 {printf "<tr>"; for (i = 1; i <= NF; i++) printf "<td>%s</td>", $i; print "</tr>"}' "$d/metrics.csv"
    echo "</table>"
done
echo "</body></html>"
