#!/bin/sh
# Reference scenes (box, office, bsdf/geom) and the command-free corpus
# files parse with the expected number of primitives of each type, counted
# independently here by a small awk tokenizer over the input files, and
# the oconv cache round trip reproduces the parsed scene exactly.
. test/e2e/lib.sh
T=$(cd "$T" && pwd)

# independent count: tokens of the files (comments dropped, quoted words
# joined), walked through "mod type id nS s.. nI i.. nR r.." / alias
tokcount() {
    cat "$@" | awk '/^[ \t]*#/ {next}
        { gsub(/"[^"]*"/, "Q"); gsub(/\047[^\047]*\047/, "Q"); for (i = 1; i <= NF; i++) tok[n++] = $i }
        END { i = 0
              while (i < n) { type = tok[i+1]; i += 3; cnt[type]++
                  if (type == "alias") { i++; continue }
                  i += 1 + tok[i]; i += 1 + tok[i]; i += 1 + tok[i] }
              for (t in cnt) print t, cnt[t] }' | sort
}
# count of the parsed scene, from oconv -p output
parsedcount() {
    oconv -p "$@" 2>/dev/null | awk 'BEGIN{h=1} NF==0{h=1; next} h{gsub(/"[^"]*"/, "Q"); gsub(/\047[^\047]*\047/, "Q"); print $2; h=0}' \
        | sort | uniq -c | awk '{print $2, $1}' | sort
}
check_counts() {  # name dir files...
    name=$1; dir=$2; shift 2
    (cd "$dir" && tokcount "$@") > "$T/want"
    (cd "$dir" && parsedcount "$@") > "$T/got"
    if [ ! -s "$T/want" ]; then fail "$name" "no primitives counted"; return; fi
    if cmp -s "$T/want" "$T/got"; then pass "$name"
    else fail "$name" "expected $(tr '\n' ' ' < "$T/want") got $(tr '\n' ' ' < "$T/got")"; fi
}
roundtrip() {  # name dir files...: scene -> cache -> text identical to scene -> text
    name=$1; dir=$2; shift 2
    (cd "$dir" && oconv "$@" > "$T/rt.oct" && oconv -p "$@" > "$T/rt1.rad" && oconv -p "$T/rt.oct" > "$T/rt2.rad") 2> "$T/err"
    if [ -s "$T/rt1.rad" ] && cmp -s "$T/rt1.rad" "$T/rt2.rad"; then pass "$name"; else fail "$name" "$(head -2 "$T/err")"; fi
}

if have_ref scenes/box; then
    B=$REF/scenes/box
    check_counts box_scene "$B" box_room.rad box_window.rad sky_clear_0101_1030.rad skyglow.rad
    check_counts box_overcast "$B" box_room.rad glass_pane.rad sky_overcast_0103_1130.rad skyglow.rad
    check_counts box_suns "$B" suns_mf1.rad suns_mf2.rad
    check_counts box_patchsuns "$B" patchsun_mf1_0101_1030.rad patchsun_mf2_0101_1030.rad sun_clear_0101_1030.rad
    check_counts box_rfluxmtx "$B" sky_rx.rad window_rx_img.rad window_rx_pts.rad window_tx.rad
    # hand-checked total for the box room: 10 polygons (floor, ceiling, 3 walls, 4 pieces of the south wall, ground)
    n=$(cd "$B" && parsedcount box_room.rad | awk '$1=="polygon"{print $2}')
    [ "$n" = 10 ] && pass box_room_polygons || fail box_room_polygons "$n"
    roundtrip box_cache_roundtrip "$B" box_room.rad box_window.rad sky_clear_0101_1030.rad skyglow.rad
    # a Radiance octree listing its scene files loads those files (from any directory)
    (cd "$B" && oconv -p box_room.rad box_window.rad sky_clear_0101_1030.rad skyglow.rad) > "$T/o1.rad" 2>/dev/null
    oconv -p "$B/box_clear.oct" > "$T/o2.rad" 2> "$T/err"
    [ -s "$T/o1.rad" ] && cmp -s "$T/o1.rad" "$T/o2.rad" && pass radiance_octree_files || fail radiance_octree_files "$(head -2 "$T/err")"
else skip box_scene "no reference box scene"; fi

if have_ref scenes/office; then
    O=$REF/scenes/office
    check_counts office_glass "$O" mat_glass.rad office.rad sky_chicago_0312_1130.rad skyglow.rad
    check_counts office_fs1s "$O" mat_fs1s.rad office.rad sky_chicago_1221_1230.rad skyglow.rad
    check_counts office_room "$O" office_room.rad
    roundtrip office_cache_roundtrip "$O" mat_fs1s.rad office.rad sky_chicago_1221_1230.rad skyglow.rad
else skip office_glass "no reference office scene"; fi

if have_ref bsdf/geom; then
    G=$REF/bsdf/geom
    check_counts cfs1_geometry "$G" slat.mat cfs1.rad
    check_counts cfs2_geometry "$G" slat.mat cfs2.rad
    check_counts cfs3_geometry "$G" prism_glass.mat cfs3.rad
    check_counts fabric_geometry "$G" fabric.rad
    check_counts glazing_geometry "$G" glazing.rad
    check_counts slat_profile_geometry "$G" slat.mat slat_profile.rad
    roundtrip cfs3_cache_roundtrip "$G" prism_glass.mat cfs3.rad
else skip cfs1_geometry "no reference bsdf geometry"; fi

CORPUS=${HELIODON_CORPUS:-$REF/../corpus/radiance-test-renders}
if [ -d "$CORPUS" ]; then
    PRE="basic.mat chrome.mat gold.mat spectral.mat patterns.mat"
    for f in $(cd "$CORPUS" && grep -L '^[[:space:]]*!' *.rad); do
        case $f in saucer.rad) continue ;; esac
        check_counts "corpus_$f" "$CORPUS" $PRE "$f"
    done
else skip corpus_counts "no corpus"; fi
