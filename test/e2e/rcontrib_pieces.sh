# rcontrib -R (record ranges as pieces) and rcmerge: pieces of any split, joined, are byte for byte
# the full run's output, in backward and photon-map mode, for pictures (one per modifier), float
# matrices, ASCII and a one-row sensor picture split inside its scanline; rcmerge refuses a
# missing range, an overlap, a piece of another run and a truncated piece.
. test/e2e/lib.sh
export SOURCE_DATE_EPOCH=1700000000
T=$(cd "$T" && pwd)   # absolute: each run below works in its own folder
roofbox_suns > "$T/box.rad"
printf 'solar1\nsolar2\n' > "$T/mods.txt"
cat > "$T/v.vf" <<'VF'
rvu -vtv -vp 0.5 0.5 0.9 -vd 0 0 -1 -vu 0 1 0 -vh 80 -vv 80
VF
X=20; Y=20; N=$((X * Y))
vwrays -ff -vf "$T/v.vf" -x $X -y $Y > "$T/rays.ff"
mkpmap -apC "$T/a.pm" 20k -apo port_m -apr 3 -n 1 "$T/box.rad" > /dev/null 2>&1 || fail pmap_build

# run NAME "rcontrib options" MODE: the full output and pieces of three splits, joined
run_case() {
    name=$1 opts=$2 fmt=$3
    full="$T/$name.full"; rm -rf "$full" "$T/$name".p*; mkdir -p "$full"
    # shellcheck disable=SC2086
    # every run in its own folder with the same -o (the header holds the command line)
    if ! (cd "$full" && rcontrib $fmt -x $X -y $Y $opts -o %s.out -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff") 2> "$T/err"; then
        fail "${name}_full" "$(head -2 "$T/err")"; return; fi
    for split in "0 $N" "0 200 200 200" "0 7 7 193 200 200"; do   # whole, two halves, uneven (inside scanlines)
        set -- $split; k=0; dirs=""
        while [ $# -gt 0 ]; do
            d="$T/$name.p$k"; rm -rf "$d"; mkdir -p "$d"; dirs="$dirs $d"
            # shellcheck disable=SC2086
            (cd "$d" && rcontrib $fmt -x $X -y $Y $opts -R "$1" "$2" -o %s.out -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff") 2> "$T/err" \
                || { fail "${name}_piece" "$(head -2 "$T/err")"; return; }
            shift 2; k=$((k + 1))
        done
        rm -rf "$T/$name.join"
        # shellcheck disable=SC2086
        if rcmerge -d "$T/$name.join" $dirs 2> "$T/err" && cmp -s "$full/solar1.out" "$T/$name.join/solar1.out" &&
            cmp -s "$full/solar2.out" "$T/$name.join/solar2.out"; then pass "${name}_split$k"
        else fail "${name}_split$k" "$(head -2 "$T/err")"; fi
    done
}
run_case back_pic "-ab 1 -ad 64 -lw 1e-3" -ffc
run_case back_float "-ab 1 -ad 64 -lw 1e-3" -fff
run_case back_ascii "-ab 1 -ad 64 -lw 1e-3" -ffa
run_case pm_pic "-ab -1 -ap $T/a.pm 40" -ffc
run_case pm_float "-ab -1 -ap $T/a.pm 40" -fff

# the full picture is a valid picture with values (not all black)
if pvalue -h -H -b -d "$T/back_pic.full/solar1.out" | awk '$1 > 0 {n++} END {exit !(n > 10)}'; then pass pic_has_light
else fail pic_has_light; fi
# photon mode's older name -apR is -R
mkdir -p "$T/apr" "$T/r0"
(cd "$T/apr" && rcontrib -ffc -x $X -y $Y -ab -1 -ap "$T/a.pm" 40 -apR 0 200 -o %s.out -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff") 2>/dev/null
(cd "$T/r0" && rcontrib -ffc -x $X -y $Y -ab -1 -ap "$T/a.pm" 40 -R 0 200 -o %s.out -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff") 2>/dev/null
if [ -s "$T/r0/solar1.out" ] && cmp -s "$T/apr/solar1.out" "$T/r0/solar1.out"; then pass apR_alias; else fail apR_alias; fi

# refusals
p="$T/back_pic"
rm -rf "$T/h0" "$T/h1" "$T/h2"; mkdir -p "$T/h0" "$T/h1" "$T/h2"
(cd "$T/h0" && rcontrib -ffc -x $X -y $Y -ab 1 -ad 64 -lw 1e-3 -R 0 210 -o %s.out -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff") 2>/dev/null
(cd "$T/h1" && rcontrib -ffc -x $X -y $Y -ab 1 -ad 64 -lw 1e-3 -R 200 200 -o %s.out -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff") 2>/dev/null
check_fails missing_range "records 210 to 399 .*missing" rcmerge "$T/m.out" "$T/h0/solar1.out"
check_fails overlap "overlap \(records 200 to 209\)" rcmerge "$T/m.out" "$T/h0/solar1.out" "$T/h1/solar1.out"
(cd "$T/h2" && rcontrib -ffc -x $X -y $Y -ab 1 -ad 64 -lw 1e-3 -seed 7 -R 200 200 -o %s.out -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff") 2>/dev/null
check_fails other_run "not a piece of the same run" rcmerge "$T/m.out" "$T/h0/solar1.out" "$T/h2/solar1.out"
check_fails other_modifier "not a piece of the same run.*MODIFIER" rcmerge "$T/m.out" "$T/h0/solar1.out" "$T/h1/solar2.out"
head -c 900 "$T/h1/solar1.out" > "$T/trunc.out"
check_fails truncated "truncated" rcmerge "$T/m.out" "$T/h0/solar1.out" "$T/trunc.out"
check_fails not_piece "not a piece" rcmerge "$T/m.out" "$p.full/solar1.out"
rm -f "$T/h2/solar2.out"
check_fails missing_file "h2/solar2.out: no such piece" rcmerge -d "$T/m.d" "$T/h0" "$T/h2"
[ ! -e "$T/m.out" ] && pass no_output_on_error || fail no_output_on_error
check_fails range_beyond "beyond the 400" rcontrib -ffc -x $X -y $Y -R 300 101 -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff"
check_fails range_needs_xy "needs -y" rcontrib -fff -R 0 10 -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff"
check_fails range_recover "not recovered" rcontrib -r -ffc -x $X -y $Y -R 0 10 -o "$T/r%s" -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff"
head -c $((24 * 300)) "$T/rays.ff" > "$T/short.ff"
check_fails short_input "inside the piece" rcontrib -ffc -x $X -y $Y -R 200 200 -o "$T/s%s" -M "$T/mods.txt" "$T/box.rad" < "$T/short.ff"
check_fails exr_piece "not OpenEXR" rcontrib -ffc -x $X -y $Y -ab -1 -ap "$T/a.pm" 40 -R 0 200 -o "$T/e%s.exr" -M "$T/mods.txt" "$T/box.rad" < "$T/rays.ff"

# a sensor file as one-row picture, split inside the row
printf '%s\n' "0.2 0.2 0.01 0 0 1" "0.5 0.5 0.01 0 0 1" "0.7 0.3 0.01 0 0 1" "0.4 0.8 0.01 0 0 1" "0.6 0.6 0.01 0 0 1" > "$T/pts.txt"
mkdir -p "$T/sf" "$T/sa" "$T/sb"
sensor() { (cd "$1" && shift && rcontrib -I -fac -x 5 -y 1 -ab 1 -ad 64 -lw 1e-3 "$@" -o s.%s -M "$T/mods.txt" "$T/box.rad" < "$T/pts.txt") 2>/dev/null; }
sensor "$T/sf"; sensor "$T/sa" -R 0 2; sensor "$T/sb" -R 2 3
if rcmerge "$T/sj.solar1" "$T/sb/s.solar1" "$T/sa/s.solar1" 2> "$T/err" && cmp -s "$T/sj.solar1" "$T/sf/s.solar1"; then pass sensor_row
else fail sensor_row "$(head -1 "$T/err")"; fi
