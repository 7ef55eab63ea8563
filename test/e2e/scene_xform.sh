#!/bin/sh
# xform and genbox: transforms, arrays, names, mirroring, scaling, nesting.
. test/e2e/lib.sh

# vertices of every polygon, one "x y z" per line (skips headers and counts)
verts() { awk '/^#/ {next} NF==3 && $2=="polygon" {p=1; n=0; next} p && NF==1 {n++; next} p && NF==3 {print $1, $2, $3} NF==0 {p=0}' "$1"; }
# compare two files of numbers with an absolute tolerance
numeq() { awk -v t="${3:-1e-9}" 'NR==FNR {a[FNR]=$0; n=FNR; next} { if (FNR>n) bad=1; split(a[FNR], x); for (i=1;i<=NF;i++) { d=x[i]-$i; if (d<0)d=-d; if (d>t || NF!=split(a[FNR],y)) bad=1 } m=FNR } END { exit (bad || m!=n) }' "$1" "$2"; }

cat > "$T/sq.rad" <<'X'
void plastic m 0 0 5 .5 .5 .5 0 0
m polygon sq 0 0 12  0 0 0  1 0 0  1 1 0  0 1 0
m sphere ball 0 0 4  1 2 3  .5
m cone cn 0 0 8  0 0 0  0 0 1  .5 .25
m ring rg 0 0 8  0 0 0  0 0 1  0 2
void glow g 0 0 4 1 1 1 2
g source sun 0 0 4  1 0 0  .5
X

# -rz 90 then -t 1 2 3: (x,y,z) -> (-y+1, x+2, z+3)
xform -rz 90 -t 1 2 3 "$T/sq.rad" > "$T/rt.rad" 2> "$T/err" || fail rz_t_runs "$(cat "$T/err")"
verts "$T/rt.rad" > "$T/rt.v"
printf '1 2 3\n1 3 3\n0 3 3\n0 2 3\n' > "$T/rt.want"
if numeq "$T/rt.v" "$T/rt.want" 1e-12; then pass rz90_t_vertices; else fail rz90_t_vertices "$(tr '\n' ' ' < "$T/rt.v")"; fi
head -1 "$T/rt.rad" | grep -q '^# xform -rz 90 -t 1 2 3' && pass header_comment || fail header_comment "$(head -1 "$T/rt.rad")"
# source direction rotated, not translated: (1,0,0) -> (0,1,0)
awk '$3=="sun"{f=1;next} f&&NF==3{print;exit}' "$T/rt.rad" > "$T/sun.v"
echo "0 1 0" > "$T/sun.want"
numeq "$T/sun.v" "$T/sun.want" 1e-12 && pass source_rotated || fail source_rotated "$(cat "$T/sun.v")"

# arrays: 3 copies stepping by +1 in x
xform -a 3 -t 1 0 0 "$T/sq.rad" > "$T/arr.rad"
n=$(grep -c ' polygon ' "$T/arr.rad"); [ "$n" -eq 3 ] && pass array_count || fail array_count "$n polygons"
verts "$T/arr.rad" | awk 'NR%4==1 {print $1}' | tr '\n' ' ' > "$T/arr.x"
[ "$(cat "$T/arr.x")" = "0 1 2 " ] && pass array_offsets || fail array_offsets "$(cat "$T/arr.x")"
# 2D array with a final transform: 2x3 copies, each moved by z+10
xform -a 2 -t 1 0 0 -a 3 -t 0 1 0 -i 1 -t 0 0 10 "$T/sq.rad" > "$T/arr2.rad"
verts "$T/arr2.rad" | awk 'NR%4==1 {print $1, $2, $3}' | sort | tr '\n' ' ' > "$T/arr2.v"
[ "$(cat "$T/arr2.v")" = "0 0 10 0 1 10 0 2 10 1 0 10 1 1 10 1 2 10 " ] && pass array_2d_final || fail array_2d_final "$(cat "$T/arr2.v")"

# -n prefixes surface identifiers only (modifiers keep their names so references resolve)
xform -n pre "$T/sq.rad" > "$T/n.rad"
grep -q '^m polygon pre.sq$' "$T/n.rad" && grep -q '^void plastic m$' "$T/n.rad" && pass name_prefix || fail name_prefix "$(grep polygon "$T/n.rad")"
oconv -p "$T/n.rad" > /dev/null 2>"$T/err" && pass name_prefix_loads || fail name_prefix_loads "$(cat "$T/err")"

# -mx mirrors x and reverses the vertex order (front side preserved)
xform -mx "$T/sq.rad" > "$T/mx.rad"
verts "$T/mx.rad" > "$T/mx.v"
printf '0 1 0\n-1 1 0\n-1 0 0\n0 0 0\n' > "$T/mx.want"
numeq "$T/mx.v" "$T/mx.want" 1e-12 && pass mirror_reverses || fail mirror_reverses "$(tr '\n' ' ' < "$T/mx.v")"
# mirroring twice restores the original order
xform -mx -my "$T/sq.rad" | xform -my > "$T/mxx.rad"
verts "$T/mxx.rad" > "$T/mxx.v"; verts "$T/mx.rad" > "$T/mx2.v"
numeq "$T/mxx.v" "$T/mx.v" 1e-12 && pass mirror_composes || fail mirror_composes "$(tr '\n' ' ' < "$T/mxx.v")"

# -s scales positions and radii (sphere, cone, ring; glow radius)
xform -s 2 "$T/sq.rad" > "$T/s.rad"
sph=$(awk '$3=="ball"{f=1;next} f&&NF==3{c=$0} f&&NF==1&&c!=""{print c, $1; exit}' "$T/s.rad")
[ "$(echo $sph)" = "2 4 6 1" ] && pass scale_sphere || fail scale_sphere "$sph"
awk '$3=="cn"{f=1;next} f&&/^ /{printf "%s ", $0} f&&NF==0{exit}' "$T/s.rad" | tr -s ' ' > "$T/cone.v"
[ "$(cat "$T/cone.v")" = " 0 0 0 0 0 2 1 0.5 " ] && pass scale_cone || fail scale_cone "$(cat "$T/cone.v")"
awk '$3=="rg"{f=1;next} f&&/^ /{printf "%s ", $0} f&&NF==0{exit}' "$T/s.rad" | tr -s ' ' > "$T/ring.v"
[ "$(cat "$T/ring.v")" = " 0 0 0 0 0 1 0 4 " ] && pass scale_ring || fail scale_ring "$(cat "$T/ring.v")"
awk '$3=="g"{f=1;next} f&&/^ /{printf "%s ", $0} f&&NF==0{exit}' "$T/s.rad" | tr -s ' ' > "$T/glow.v"
[ "$(cat "$T/glow.v")" = " 1 1 1 4 " ] && pass scale_glow_radius || fail scale_glow_radius "$(cat "$T/glow.v")"

# -I inverts: sphere -> bubble, cone -> cup, polygon reversed, ring normal negated
xform -I "$T/sq.rad" > "$T/inv.rad"
grep -q '^m bubble ball$' "$T/inv.rad" && grep -q '^m cup cn$' "$T/inv.rad" && pass invert_types || fail invert_types
verts "$T/inv.rad" | head -1 | grep -q '^ *0 1 0$' && pass invert_polygon || fail invert_polygon "$(verts "$T/inv.rad" | head -1)"

# nested !xform inside a file in another directory: commands run in that file's directory
mkdir -p "$T/sub"
cp "$T/sq.rad" "$T/sub/inner.rad"
printf '!xform -t 0 0 5 inner.rad\n' > "$T/sub/outer.rad"
xform -t 10 0 0 "$T/sub/outer.rad" > "$T/nest.rad" 2> "$T/err"
verts "$T/nest.rad" | head -1 > "$T/nest.v"; echo "10 0 5" > "$T/nest.want"
numeq "$T/nest.v" "$T/nest.want" 1e-12 && pass nested_xform || fail nested_xform "$(cat "$T/err" "$T/nest.v")"
# -c keeps commands, piped through an equivalent xform
xform -c -n q -t 10 0 0 "$T/sub/outer.rad" > "$T/c.rad"
grep -q '^!xform -t 0 0 5 inner.rad | xform -n q -t 10 0 0$' "$T/c.rad" && pass no_expand || fail no_expand "$(grep '^!' "$T/c.rad")"
# the kept command gives the same result when expanded from the file's directory
cp "$T/c.rad" "$T/sub/c.rad"
xform "$T/sub/c.rad" > "$T/c2.rad" 2>/dev/null
verts "$T/c2.rad" | head -1 > "$T/c2.v"
numeq "$T/c2.v" "$T/nest.want" 1e-12 && pass no_expand_equivalent || fail no_expand_equivalent "$(cat "$T/c2.v")"
# transform words are appended to the strings of function-file primitives
printf 'void brightfunc p 2 f f.cal 0 0\nvoid mesh ms 1 a.rtm 0 0\n' | xform -a 2 -rz 30 > "$T/fn.rad"
grep -q '^2 f f.cal$' "$T/fn.rad" && grep -q '^6 f f.cal -i 1 -rz 30$' "$T/fn.rad" && grep -q '^5 a.rtm -i 1 -rz 30$' "$T/fn.rad" \
    && pass strings_get_transform || fail strings_get_transform "$(grep -E '^[0-9] ' "$T/fn.rad" | tr '\n' '|')"

# errors
check_fails bad_option_arg "expected 3 numbers" xform -t 1 2 "$T/sq.rad"
check_fails missing_file "cannot open scene file .*nothere.rad" xform -t 1 0 0 "$T/nothere.rad"
printf 'void polygon p 0 0 6 0 0 0 1 0 0\n' > "$T/badpoly.rad"
check_fails bad_polygon "badpoly.rad:1: .*n >= 3" xform -t 1 0 0 "$T/badpoly.rad"

# genbox: six outward polygons named like Radiance's, volume by the divergence theorem
vol() {  # closed polygon mesh volume: sum over faces of (v0 . (area normal)) / 3, triangle fans
    awk '/^#/ {next} NF==3 && $2=="polygon" {p=1; k=0; next} p && NF==3 {x[k]=$1; y[k]=$2; z[k]=$3; k++; next}
         NF==0 && p { for (i=1;i<k-1;i++) { ax=x[i]-x[0]; ay=y[i]-y[0]; az=z[i]-z[0]; bx=x[i+1]-x[0]; by=y[i+1]-y[0]; bz=z[i+1]-z[0];
                cx=ay*bz-az*by; cy=az*bx-ax*bz; cz=ax*by-ay*bx; V+=(x[0]*cx+y[0]*cy+z[0]*cz)/6 } p=0 }
         END { printf "%.9f\n", V }' "$1"; }
genbox mat box 2 3 4 > "$T/box.rad"
[ "$(grep -c ' polygon box\.' "$T/box.rad")" -eq 6 ] && pass genbox_faces || fail genbox_faces
for f in 1540 4620 2310 3267 5137 6457; do grep -q "^mat polygon box.$f\$" "$T/box.rad" || fail genbox_names "box.$f missing"; done
v=$(vol "$T/box.rad"); close "$v" 24 1e-9 && pass genbox_volume || fail genbox_volume "$v"
genbox mat box 2 3 4 -i > "$T/boxi.rad"
v=$(vol "$T/boxi.rad"); close "$v" -24 1e-9 && pass genbox_inverted || fail genbox_inverted "$v"
# bevelled box: volume = box - 12 edge prisms (cross-section d^2/2) - 8 corner
# pieces; the kept part of a corner d-cube is integrated numerically from the
# half-space description of the bevel planes (independent of genbox's polygons)
genbox mat bb 2 3 4 -b .2 > "$T/bev.rad"
[ "$(grep -c ' polygon bb\.' "$T/bev.rad")" -eq 26 ] && pass genbox_bevel_count || fail genbox_bevel_count
v=$(vol "$T/bev.rad")
# Monte Carlo-free expectation: grid integration of the bevelled solid's indicator
want=$(awk -v X=2 -v Y=3 -v Z=4 -v d=.2 'BEGIN { N=200; c=0; h=d/N;
    # a corner d-cube: kept where (d-x)+(d-y)<=d etc. i.e. distances to faces a,b with a+b>=d and a+b+c>=2d
    for (i=0;i<N;i++) for (j=0;j<N;j++) for (k=0;k<N;k++) { a=(i+.5)*h; b=(j+.5)*h; e=(k+.5)*h;
        if (a+b>=d && b+e>=d && a+e>=d && a+b+e>=2*d) c++ }
    corner=c*h*h*h; prism=d*d/2;
    V=X*Y*Z - 4*prism*((X-2*d)+(Y-2*d)+(Z-2*d)) - 8*(d*d*d-corner); printf "%.9f\n", V }')
close "$v" "$want" 1e-4 && pass genbox_bevel_volume || fail genbox_bevel_volume "$v vs $want"
genbox mat rb 2 3 4 -r .2 > "$T/rnd.rad"
[ "$(grep -c ' polygon rb\.' "$T/rnd.rad")" -eq 6 ] && [ "$(grep -c ' cylinder rb\.' "$T/rnd.rad")" -eq 12 ] \
    && [ "$(grep -c ' sphere rb\.' "$T/rnd.rad")" -eq 8 ] && pass genbox_round || fail genbox_round
printf 'void plastic mat 0 0 5 1 1 1 0 0\n' > "$T/mat.rad"
oconv -p "$T/mat.rad" "$T/rnd.rad" "$T/bev.rad" > /dev/null 2>"$T/err" && pass genbox_output_loads || fail genbox_output_loads "$(cat "$T/err")"
check_fails genbox_bad_size "positive" genbox mat b 1 0 1
check_fails genbox_bad_radius "less than half" genbox mat b 1 1 1 -r .6
# genbox | xform reproduces the office desk polygons written by Radiance's genbox | xform
if have_ref scenes/office; then
    genbox desk_mat desk 1.6 .8 .03 | xform -t 1 1.1 .72 > "$T/desk.rad"
    grep '^desk_mat polygon desk\.' "$REF/scenes/office/office.rad" | awk '{for(i=7;i<=NF;i+=3) print $i, $(i+1), $(i+2)}' > "$T/desk.want"
    verts "$T/desk.rad" > "$T/desk.v"
    numeq "$T/desk.v" "$T/desk.want" 1e-9 && pass genbox_matches_radiance || fail genbox_matches_radiance
else skip genbox_matches_radiance "no reference office scene"; fi
