#!/bin/sh
# gendaylit and gensky against Radiance 6.1 (../shared/ref/sky/gendaylit,
# gensky): every reference command of the manifest is run; words must be
# identical, numbers within 0.5 % (absolute 2e-6 for the 6-decimal sun
# vectors and Perez coefficients near zero, or one unit of the last printed
# decimal, the ground brightness included; the first, command-line comment
# line is skipped).  Warnings for "error skies" must match Radiance's text.
. test/e2e/lib.sh
S=$REF/sky
if ! have_ref sky/gendaylit; then skip all "no reference folder $S/gendaylit"; exit 0; fi
TOL=${SKY_TOL:-0.005}
grep -o '"command": "gen\(daylit\|sky\) [^"]*"' "$S/manifest.json" | sed 's/^"command": "//; s/"$//' > "$T/cmds"
while read -r cmd; do
    prog=${cmd%% *}
    args=$(echo "$cmd" | sed "s/^$prog //; s/ >.*//")
    out=$(echo "$cmd" | sed 's/.*> *//')
    n=$(basename "$out" .rad)_$prog
    # shellcheck disable=SC2086
    if ! (cd "$S" && $prog $args) > "$T/$n.rad" 2> "$T/$n.err"; then
        fail "$n" "$prog failed: $(head -2 "$T/$n.err" | tr '\n' ' ')"; continue
    fi
    res=$(awk -v tol="$TOL" '
        FNR == 1 { f++ }
        FNR > 1 { for (i = 1; i <= NF; i++) w[f, ++nw[f]] = $i }
        END { if (nw[1] != nw[2]) { printf "%d words vs %d", nw[1], nw[2]; exit 1 }
            worst = 0; bad = ""
            for (i = 1; i <= nw[1]; i++) { a = w[1,i]; b = w[2,i]; t = tol
                if (a == b) continue
                if (a ~ /^-?[0-9.]+(e[-+][0-9]+)?$/ && b ~ /^-?[0-9.]+(e[-+][0-9]+)?$/) {
                    d = a - b; if (d < 0) d = -d; m = b < 0 ? -b : b
                    u = 0; if (b !~ /e/ && index(b, ".")) u = 10 ^ -(length(b) - index(b, "."))
                    if (d <= 2e-6 || d <= t * m || d <= u * 1.01) { if (m > 0 && d / m > worst) worst = d / m; continue }
                    if (m > 0 && d / m > worst) worst = d / m }
                bad = bad " [" i ": " a " vs " b "]" }
            printf "worst %.4f%%%s", 100 * worst, bad; exit bad != "" }' "$T/$n.rad" "$S/$out")
    if [ $? -eq 0 ]; then pass "$n ($res)"; else fail "$n" "$res"; fi
    if [ -f "$S/$out.stderr.txt" ]; then
        if cmp -s "$T/$n.err" "$S/$out.stderr.txt"; then pass "${n}_warning"; else fail "${n}_warning" "$(cat "$T/$n.err")"; fi
    fi
done < "$T/cmds"

# bad inputs: clear messages, non-zero exit
check_fails gendaylit_no_mode 'one of -W, -G, -L, -P or -E' gendaylit 6 21 12 -a 40
check_fails gendaylit_bad_month 'bad month .13' gendaylit 13 1 12 -W 100 100
check_fails gendaylit_bad_day 'bad day .31. for month 2' gendaylit 2 31 12 -W 100 100
check_fails gendaylit_bad_hour "unknown time zone 'x' in '12x'" gendaylit 2 3 12x -W 100 100
check_fails gendaylit_bad_value 'expected a number, found "abc"' gendaylit 2 3 12 -W abc 100
check_fails gendaylit_negative 'negative value' gendaylit 2 3 12 -W -5 100
check_fails gendaylit_bad_O 'expected 0, 1 or 2' gendaylit 2 3 12 -W 5 100 -O 3
check_fails gensky_bad_zone "unknown time zone 'XYZ'" gensky 6 21 14:30XYZ +s
check_fails gensky_bad_option 'unknown option -q' gensky 6 21 12 -q
check_fails gensky_bad_refl 'reflectance out of range' gensky 6 21 12 -g 2
# quirk: gendaylit's -O takes a separate argument (-O1 is not accepted)
check_fails gendaylit_O1_glued 'unknown option -O1|expects' gendaylit 6 21 12 -W 100 100 -O1

# gensky explicit brightness options (no reference files: analytic values)
gensky 6 21 12 -c -b 10 -a 40 -o 0 -m 0 > "$T/b.rad"
if grep -q '^3 2 1.000e+01 ' "$T/b.rad"; then pass gensky_b; else fail gensky_b "$(tail -1 "$T/b.rad")"; fi
gensky 6 21 12 +s -r 1e6 -a 40 -o 0 -m 0 > "$T/r.rad"
if grep -q '^3 1.000e+06 1.000e+06 1.000e+06$' "$T/r.rad"; then pass gensky_r; else fail gensky_r "$(grep '^3 ' "$T/r.rad")"; fi
# -R: direct HORIZONTAL irradiance over the 0.5 degree disk (solid angle
# 5.98e-5 sr as Radiance): sun vector z = 0.958563 here, so
# 800 / (5.98e-5 * 0.958563) = 1.39563e+07
gensky 6 21 12 +s -R 800 -a 40 -o 0 -m 0 > "$T/R.rad"
if grep -q '^3 1.396e+07 ' "$T/R.rad" && grep -q ' 0.958563$' "$T/R.rad"; then pass gensky_R; else fail gensky_R "$(grep '^3 ' "$T/R.rad")"; fi
# sun within 3 degrees of the zenith: Radiance lowers it to 87 degrees, with a
# warning on stderr and in the output (sun z = sin 87 deg = 0.998630)
gensky 6 21 12 +s -a 23 -o 0 -m 0 > "$T/z.rad" 2> "$T/z.err"
if grep -q 'reducing altitude to 87 degrees' "$T/z.err" && grep -q '^# warning - sun too close to zenith' "$T/z.rad" &&
    grep -q '^7 1 .* 0.998630$' "$T/z.rad"; then pass gensky_zenith_clamp; else fail gensky_zenith_clamp "$(tail -1 "$T/z.rad")"; fi
# uniform sky: ground = rfl * zenith (normalisation 1)
gensky 6 21 12 -u -b 5 -g 0.4 -a 40 -o 0 -m 0 > "$T/u.rad"
if grep -q '^3 3 5.000e+00 2.000e+00$' "$T/u.rad"; then pass gensky_uniform; else fail gensky_uniform "$(tail -1 "$T/u.rad")"; fi
