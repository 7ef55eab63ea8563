#!/bin/bash
# heliodon pipeline preflight: every input of a case is checked before anything long starts.
# Called by heliodon.mk with the case's variables in HD_* environment variables; OUT = $1.
# Each failure names the make variable or the file at fault and exits 1.
set -u
OUT=$1
die() { echo "heliodon-pipeline: $*" >&2; exit 1; }
[ -n "$HD_WEATHER" ] || die "WEATHER is not set (an EPW or WEA file)"
[ -r "$HD_WEATHER" ] || die "WEATHER=$HD_WEATHER: weather file not found"
[ -n "$HD_GROUPS" ] || die "GROUPS is not set (the names of the window groups)"
[ -n "$HD_VIEWS$HD_SENSORS" ] || die "VIEWS and SENSORS are both empty: nothing to compute"
# RAYPATH directories for BSDF files named in material files
find_raypath() {
    local f=$1 d
    case $f in /*) [ -r "$f" ]; return ;; esac
    IFS=: read -ra dirs <<< "${RAYPATH:-.}"
    for d in "${dirs[@]}"; do [ -r "$d/$f" ] && return 0; done
    return 1
}
declare -A seen
allmods=""
for g in $HD_GROUPS; do
    [[ $g =~ ^[A-Za-z_][A-Za-z0-9_]*$ ]] || die "GROUPS: '$g' is not a valid group name (letters, digits, _)"
    [ -z "${seen[$g]:-}" ] || die "GROUPS: group '$g' is named twice"
    seen[$g]=1
    geom=$(printenv "HD_GEOM_$g"); mod=$(printenv "HD_MOD_$g"); mat=$(printenv "HD_MAT_$g")
    klems=$(printenv "HD_KLEMS_$g"); up=$(printenv "HD_UP_$g")
    [ -n "$geom" ] || die "group '$g': GEOM_$g is not set (the scene file holding its surfaces)"
    for f in $geom; do [ -r "$f" ] || die "group '$g': GEOM_$g=$f: file not found"; done
    [ -n "$mat" ] || die "group '$g': MAT_$g is not set (glass, a BSDF .xml or a Radiance .rad material file)"
    case " $allmods " in *" $mod "*) die "group '$g': MOD_$g=$mod is the modifier of another group too";; esac
    allmods="$allmods $mod"
    case $mat in
        glass) ;;
        *.xml) [ -r "$mat" ] || die "group '$g': MAT_$g=$mat: BSDF file not found"
               set -- $up; [ $# = 3 ] || die "group '$g': UP_$g='$up': expected an up vector 'x y z'" ;;
        *.rad) [ -r "$mat" ] || die "group '$g': MAT_$g=$mat: material file not found"
               grep -Eq "^[^#]*[[:space:]]$mod([[:space:]]|\$)" "$mat" || \
                   die "group '$g': MAT_$g=$mat does not define the group's modifier '$mod' (MOD_$g)"
               for x in $(awk '$2 == "BSDF" {print $6}' "$mat"); do
                   find_raypath "$x" || die "group '$g' (MAT_$g=$mat): BSDF file $x not found in RAYPATH=$RAYPATH (set BSDFPATH)"
               done ;;
        *) die "group '$g': MAT_$g=$mat: expected glass, a .xml BSDF file or a .rad material file" ;;
    esac
    if [ "$HD_SKYMETHOD" = 3pm ]; then
        [ -n "$klems" ] && [ -r "$klems" ] || die "group '$g': SKYMETHOD=3pm: Klems BSDF for $g not found (KLEMS_$g='$klems')"
    fi
    n=$(xform $geom 2>/dev/null | awk -f "$(dirname "$0")/scene.awk" -v mode=count -v mods="$mod" -v name="$geom" | awk '{print $2}')
    [ "${n:-0}" -gt 0 ] || die "group '$g': no surface with modifier '$mod' (MOD_$g) in GEOM_$g=$geom"
done
for f in $HD_SCENE; do [ -r "$f" ] || die "SCENE: $f: file not found"; done
if [ -n "$HD_GROUND" ]; then
    n=$(xform $HD_SCENE 2>/dev/null | awk -f "$(dirname "$0")/scene.awk" -v mode=count -v mods="$HD_GROUND" -v name=SCENE | awk '{s += $2} END {print s + 0}')
    [ "$n" -gt 0 ] || die "GROUND_MOD=$HD_GROUND: no surface with this modifier in SCENE ($HD_SCENE)"
fi
# weather: location header and daylight hours (whatever the views)
printf 'rview -vta -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180\n' > "$OUT/preflight.vf"
pmcompose -P -w "$HD_WEATHER" -vf "$OUT/preflight.vf" -o /dev/null > /dev/null 2> "$OUT/preflight.err" ||
    die "WEATHER: $(sed 's/^pmcompose: //' "$OUT/preflight.err" | head -2 | tr '\n' ' ')"
rm -f "$OUT/preflight.vf" "$OUT/preflight.err"
declare -A vseen
for v in $HD_VIEWS; do
    [ -r "$v" ] || die "VIEWS: $v: view file not found"
    b=$(basename "$v"); b=${b%.*}
    [ -z "${vseen[$b]:-}" ] || die "VIEWS: two views named '$b'"
    vseen[$b]=1
done
for v in $HD_GLARE_VIEWS; do
    [ -r "$v" ] || die "GLARE_VIEWS: $v: view file not found"
    pmcompose -P -w "$HD_WEATHER" -vf "$v" -o /dev/null > /dev/null 2> "$OUT/preflight.err" ||
        die "GLARE_VIEWS: $v: $(sed 's/^pmcompose: //' "$OUT/preflight.err" | head -2 | tr '\n' ' ')(glare needs a 180-degree fisheye view: -vta or -vth with -vh 180 -vv 180)"
done
for s in $HD_SENSORS; do
    [ -r "$s" ] || die "SENSORS: $s: sensor file not found"
    bad=$(awk 'NF > 0 && $1 !~ /^#/ && (NF < 6 || $1 !~ /^[-+.0-9eE]+$/) {print FILENAME ": line " NR ": expected x y z dx dy dz"; exit}' "$s")
    [ -z "$bad" ] || die "SENSORS: $bad"
    n=$(awk 'NF >= 6 && $1 !~ /^#/' "$s" | wc -l)
    [ "$n" -gt 0 ] || die "SENSORS: $s: no sensor points"
done
rm -f "$OUT/preflight.err"
exit 0
