#!/bin/bash
# brightfunc patterns on emitting materials through the .cal module:
# the two sky functions (gensky's skybright.cal, gendaylit's perezlum.cal)
# give the same values through lib/*.cal as natively (HELIODON_SKY_CAL=1
# forces the .cal path; by default the file RAYPATH finds is the sky
# function: heliodon's own library file is computed by the equivalent C, any
# other file is evaluated), and a sky function file of our own with real
# arguments and a transform gives its analytic values.
. test/e2e/lib.sh
T=$(cd "$T" && pwd)
# rays from the origin to the sky: 5 elevations x 8 azimuths, and below the horizon
awk 'BEGIN{pi=3.14159265358979; for(e=-10;e<=80;e+=22.5) for(a=0;a<360;a+=45){t=e*pi/180; p=a*pi/180; printf "0 0 0 %.9f %.9f %.9f\n", cos(t)*cos(p), cos(t)*sin(p), sin(t)}}' > "$T/dirs.txt"
n=$(wc -l < "$T/dirs.txt")
sky() {  # sky NAME generator-command
    $2 > "$T/$1.rad" 2>"$T/err" || { fail "$1_generate" "$(cat "$T/err")"; return; }
    printf 'skyfunc glow skyglow 0 0 4 1 1 1 0\nskyglow source sky 0 0 4 0 0 1 180\nskyfunc glow groundglow 0 0 4 1 1 1 0\ngroundglow source ground 0 0 4 0 0 -1 180\n' >> "$T/$1.rad"
    rtrace -h -ab 0 "$T/$1.rad" < "$T/dirs.txt" > "$T/$1.native" 2>"$T/err" || { fail "$1_native" "$(cat "$T/err")"; return; }
    HELIODON_SKY_CAL=1 rtrace -h -ab 0 "$T/$1.rad" < "$T/dirs.txt" > "$T/$1.cal" 2>"$T/err" || { fail "$1_cal" "$(cat "$T/err")"; return; }
    res=$(paste "$T/$1.native" "$T/$1.cal" | awk '{for(i=1;i<=3;i++){d=$i-$(i+3); if(d<0)d=-d; m=$i<0?-$i:$i; if(d>1e-6*m) bad++} if ($1>0) lit++} END{print NR, lit+0, bad+0}')
    set -- $1 $res
    if [ "$2" -eq "$n" ] && [ "$3" -ge $((n / 2)) ] && [ "$4" -eq 0 ]; then pass "$1_cal_equals_native"
    else fail "$1_cal_equals_native" "$2 rays, $3 lit, $4 differ"; fi
}
sky gensky_clear "gensky 3 21 12 +s -a 40 -o -100 -m -105"
sky gensky_overcast "gensky 3 21 12 -c -a 40 -o -100 -m -105"
sky gensky_uniform "gensky 3 21 12 -u -a 40 -o -100 -m -105"
sky gendaylit "gendaylit 3 21 12 -a 40 -o -100 -m -105 -W 600 150"

# a function file of our own: brightness = A1 + A2*Dx (after the transform
# -rz 90, the pattern's x axis is the world's -y ... Dx_pattern = Dy_world)
cat > "$T/mysky.cal" <<'CAL'
{ test sky: linear in the pattern frame's x }
lin = A1 + A2*Dx + 0*arg(0);
CAL
printf 'void brightfunc mine 4 lin %s/mysky.cal -rz 90 0 2 .5 .25\nmine glow g 0 0 4 2 2 2 0\ng source s 0 0 4 0 0 1 180\n' "$T" > "$T/mine.rad"
rtrace -h -ab 0 "$T/mine.rad" < "$T/dirs.txt" > "$T/mine.out" 2>"$T/err" || fail own_sky "$(cat "$T/err")"
bad=$(paste "$T/dirs.txt" "$T/mine.out" | awk '$6 > 0 {want=2*(.5+.25*$5); d=$7-want; if(d<0)d=-d; if(d>1e-6*want) b++; n++} END{print n+0, b+0}')
[ "${bad% *}" -ge 10 ] && [ "${bad#* }" -eq 0 ] && pass own_sky_function_with_transform || fail own_sky_function_with_transform "$bad"

# errors name the file and what is missing
printf 'void brightfunc bad 2 nosuch %s/mysky.cal 0 0\nbad glow g 0 0 4 1 1 1 0\ng source s 0 0 4 0 0 1 180\n' "$T" > "$T/bad.rad"
check_fails undefined_pattern_variable "nosuch" rtrace -h "$T/bad.rad" < /dev/null
printf 'void brightfunc bad 2 x nofile.cal 0 0\nbad glow g 0 0 4 1 1 1 0\ng source s 0 0 4 0 0 1 180\n' > "$T/bad2.rad"
check_fails missing_function_file "nofile.cal" rtrace -h "$T/bad2.rad" < /dev/null
# the .cal path is really taken when forced: a broken perezlum.cal found first through RAYPATH
# (heliodon's own library is searched after RAYPATH) makes it fail, naming the file
mkdir -p "$T/brokenlib" && echo 'skybright = 1 + ;' > "$T/brokenlib/perezlum.cal"
check_fails forced_cal_path_loads_library "brokenlib/perezlum.cal, line 1" env HELIODON_SKY_CAL=1 RAYPATH="$T/brokenlib" rtrace -h "$T/gendaylit.rad" < /dev/null
# ... and by default too: the sky function is the file RAYPATH finds (heliodon's
# own library file is computed by the equivalent C, any other is evaluated)
check_fails raypath_cal_file_is_used "brokenlib/perezlum.cal, line 1" env RAYPATH="$T/brokenlib" rtrace -h "$T/gendaylit.rad" < /dev/null
mkdir -p "$T/mylib" && echo 'skybright = 7 + 0*A1;' > "$T/mylib/perezlum.cal"
v=$(echo '0 0 0 0 0 1' | RAYPATH="$T/mylib" rtrace -h -ab 0 "$T/gendaylit.rad" 2>&1)
if close "${v%%	*}" 7 1e-9; then pass own_perezlum_cal_used; else fail own_perezlum_cal_used "$v (want 7)"; fi
