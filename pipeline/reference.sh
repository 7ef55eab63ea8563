#!/bin/bash
# reference.sh: the backward reference of "make reference" (pipeline/reference.mk, heliodon-pipeline(7)).
#   reference.sh pick VIEW.csv N [RECORDS [PAIR]]   the records to render: RECORDS (commas or spaces)
#       when given, otherwise the hour of largest disagreement between the methods of VIEW.csv (largest
#       spread max - min of their DGPs; with PAIR "A B", two of pm 3pm imageless 5pm: the largest
#       DGP_A - DGP_B, the hours where A is furthest above B) and the next largest on other days, N in
#       all (fewer when the CSV has fewer hours with two methods)
#   reference.sh sky RECORD records.txt site.txt   gendaylit's sky with its exact sun for that weather
#       record (-W DNI DHI), the sky and ground glow hemispheres driven by its skyfunc
#   reference.sh stats VIEWFILE PICTURE   "E_v Lmed Lmean Lmax DGP DGI omega" of the picture
#   reference.sh table DIR VIEWFILE IMAGELESS.csv FALSECOLOR-OPTIONS OS RECORD...   DIR/table.csv and
#       DIR/table.html: per record and picture (ref_R: the reference at OS x OS rays per pixel, box-filtered,
#       ref1_R: one ray per pixel, pm_R, 3pm_R, 5pm_R when present) E_v, median, mean and maximum
#       luminance, DGP, DGI and the glare sources' solid angle from evalglare -d (the maximum by
#       pextrem -o), the imageless method's E_v and DGP from its CSV; false-colour PNGs (falsecolor,
#       cbdmreport -png) on one scale
set -eu
case $1 in
pick)
    csv=$2; n=$3; recs=${4:-}; pair=${5:-}
    if [ -n "$recs" ]; then
        for r in $(echo "$recs" | tr ',' ' '); do
            awk -F, -v r="$r" 'NR > 1 && $1 == r {f = 1} END {exit !f}' "$csv" ||
                { echo "reference.sh: REF_HOURS: record '$r' has no result in $csv (expected a daylight record of the run)" >&2; exit 1; }
            echo "$r"
        done
        exit 0
    fi
    ca=0; cb=0
    if [ -n "$pair" ]; then
        col() { case $1 in pm) echo 5;; 3pm) echo 6;; imageless) echo 7;; 5pm) echo 8;; *) return 1;; esac; }
        set -- $pair
        { [ $# = 2 ] && ca=$(col "$1") && cb=$(col "$2") && [ "$ca" != "$cb" ]; } ||
            { echo "reference.sh: REF_PAIR='$pair': expected two different methods of pm 3pm imageless 5pm" >&2; exit 1; }
    fi
    awk -F, -v a="$ca" -v b="$cb" 'NR > 1 && a {if ($a != "" && $b != "") printf "%.6f %d %d/%d\n", $a - $b, $1, $2, $3; next}
        NR > 1 {k = 0; for (j = 5; j <= 8; j++) if ($j != "") {v = $j + 0; if (!k || v > hi) hi = v; if (!k || v < lo) lo = v; k++}
        if (k >= 2) printf "%.6f %d %d/%d\n", hi - lo, $1, $2, $3}' "$csv" | sort -k1,1gr -k2,2n |
        awk -v n="$n" '{r[NR] = $2; d[NR] = $3} END {
            for (i = 1; i <= NR && k < n; i++) if (i == 1 || !(d[i] in day)) {print r[i]; day[d[i]] = 1; used[i] = 1; k++}
            for (i = 1; i <= NR && k < n; i++) if (!(i in used)) {print r[i]; k++}}'
    ;;
sky)
    rec=$2
    read -r mo da hr dni dhi < <(awk -v r="$rec" '$1 == r {print $2, $3, $4, $5, $6}' "$3") || true
    [ -n "${dhi:-}" ] || { echo "reference.sh: record $rec not in $3" >&2; exit 1; }
    read -r lat lon mer < "$4"
    gendaylit "$mo" "$da" "$hr" -a "$lat" -o "$lon" -m "$mer" -W "$dni" "$dhi"
    printf '%s\n' "skyfunc glow ref_sky_glow 0 0 4 1 1 1 0" "ref_sky_glow source ref_sky 0 0 4 0 0 1 180" \
        "skyfunc glow ref_ground_glow 0 0 4 1 1 1 0" "ref_ground_glow source ref_ground 0 0 4 0 0 -1 180"
    ;;
table)
    dir=$2; vf=$3; imgl=$4; fc=$5; os=$6; shift 6
    stats() { "$0" stats "$vf" "$1"; }
    label() { case $1 in ref) echo "reference, ${os}x$os rays per pixel, box-filtered";; ref1) echo "reference, one ray per pixel";;
        pm) echo "PM-CBDM";; 3pm) echo "3PM";; 5pm) echo "5PM";; imageless) echo "imageless";; esac; }
    {
        echo "record,month,day,hour,method,Ev,Lmed,Lmean,Lmax,DGP,DGI,omega"
        for r in "$@"; do
            when=$(awk -F, -v r="$r" 'NR > 1 && $1 == r {print $2 "," $3 "," $4; exit}' "$dir/../$(basename "$dir" _ref).csv")
            for m in ref ref1 pm 3pm 5pm; do
                [ -s "$dir/${m}_$r.hdr" ] || continue
                echo "$r,$when,$m,$(stats "$dir/${m}_$r.hdr" | tr ' ' ,)"
            done
            if [ -s "$imgl" ]; then
                awk -F, -v r="$r" -v w="$when" 'NR > 1 && $1 == r {printf "%d,%s,imageless,%s,,,,%s,,\n", r, w, $5, $6}' "$imgl"
            fi
        done
    } > "$dir/table.csv.tmp"
    mv -f "$dir/table.csv.tmp" "$dir/table.csv"
    {
        echo "<h3>Against the backward reference with the exact sun</h3>"
        echo "<p>Per hour: the converged backward rendering with gendaylit's sun and sky (oversampled and box-filtered; the same at one ray per pixel) and each method's picture of the hour, all through evalglare; E_v in lx, luminances in cd/m&#178;, &omega; the glare sources' solid angle in sr; differences against the oversampled reference.</p>"
        for r in "$@"; do
            awk -F, -v r="$r" 'NR > 1 && $1 == r && $5 == "ref" {printf "<h4>Record %d, %d/%d %.2f h</h4>\n", $1, $2, $3, $4; exit}' "$dir/table.csv"
            echo "<table><tr><th>picture</th><th>E_v</th><th>&Delta;E_v</th><th>L median</th><th>L mean</th><th>L max</th><th>DGP</th><th>&Delta;DGP</th><th>DGI</th><th>&omega; sources</th></tr>"
            awk -F, -v r="$r" -v os="$os" 'BEGIN {split("ref ref1 pm 3pm 5pm imageless", k, " "); split("reference (" os "x" os " rays per pixel, box-filtered)|reference (one ray per pixel)|PM-CBDM|3PM|5PM|imageless", l, "|"); for (i in k) lab[k[i]] = l[i]}
                NR > 1 && $1 == r {m[++n] = $0} NR > 1 && $1 == r && $5 == "ref" {e = $6; g = $10}
                function f(x, fmt) {return x == "" ? "" : sprintf(fmt, x)}
                END {for (i = 1; i <= n; i++) {split(m[i], a, ","); de = e > 0 ? sprintf("%+.1f %%", 100 * (a[6] / e - 1)) : ""
                    printf "<tr><td>%s</td><td>%.0f</td><td>%s</td><td>%s</td><td>%s</td><td>%s</td><td>%.3f</td><td>%+.3f</td><td>%s</td><td>%s</td></tr>\n",
                        lab[a[5]], a[6], de, f(a[7], "%.0f"), f(a[8], "%.0f"), f(a[9], "%.4g"), a[10], a[10] - g, f(a[11], "%.1f"), f(a[12], "%.4f")}}' "$dir/table.csv"
            echo "</table><p>"
            for m in ref ref1 pm 3pm 5pm; do
                [ -s "$dir/${m}_$r.hdr" ] || continue
                falsecolor -i "$dir/${m}_$r.hdr" $fc -l cd/m2 > "$dir/fc_${m}_$r.hdr"
                cbdmreport -png "$dir/fc_${m}_$r.png" "$dir/fc_${m}_$r.hdr"
                rm -f "$dir/fc_${m}_$r.hdr"
                echo "<figure style=\"display:inline-block;margin:4px\"><img src=\"$(basename "$dir")/fc_${m}_$r.png\" alt=\"$m record $r\"><figcaption>$(label "$m")</figcaption></figure>"
            done
            echo "</p>"
        done
    } > "$dir/table.html.tmp"
    mv -f "$dir/table.html.tmp" "$dir/table.html"
    ;;
stats)
    # E_v Lmed Lmean Lmax DGP DGI omega of PICTURE in VIEWFILE's view
    g=$(evalglare -d -vf "$2" "$3" | awk -F: '/^dgp,av_lum,E_v/ {split($2, v, " "); printf "%.6g %.6g %.6g %.6g %.6g %.6g", v[3], v[20], v[2], v[1], v[6], v[11]}')
    mx=$(pextrem -o "$3" | awk 'NR == 2 {printf "%.6g", 179 * (0.265074126 * $3 + 0.670114631 * $4 + 0.064811243 * $5)}')
    [ -n "$g" ] && [ -n "$mx" ] || { echo "reference.sh: no glare result for $3" >&2; exit 1; }
    set -- $g; echo "$1 $2 $3 $mx $4 $5 $6"
    ;;
*) echo "reference.sh: expected pick, sky, stats or table, not '$1'" >&2; exit 1 ;;
esac
