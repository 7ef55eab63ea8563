# mkpmap -apJ refuses pieces that are not the shards of one run: a missing shard, a shard given
# twice, a shard of another photon count, seed or scene, a shard mixed with a whole map; the
# complete set in any order merges into the single run's photons.
. test/e2e/lib.sh
{ roofbox_suns; printf 'void light solar3 0 0 3 1e6 1e6 1e6\nsolar3 source sun3 0 0 4 -0.2 0.1 1 0.533\n'; } > "$T/box.rad"
sed 's/floormat 0 0 5 .5 .5 .5/floormat 0 0 5 .4 .4 .4/' "$T/box.rad" > "$T/box2.rad"
body() { off=$(grep -abo -m1 'FORMAT=heliodon_contrib_pmap' "$1" | cut -d: -f1); tail -c +$((off + 30)) "$1"; }
same_body() { body "$1" > "$T/body1"; body "$2" > "$T/body2"; [ -s "$T/body1" ] && cmp "$T/body1" "$T/body2"; }
mk() { mkpmap -apC "$T/$1" 30k -apo port_m "${@:2}"; }
check whole mk w.pm -apr 5 "$T/box.rad"
for k in 0 1 2; do check shard$k mk s$k.pm -apr 5 -apH $k 3 "$T/box.rad"; done
check header_lines grep -aq '^PMAPSHARD= 1 3$' "$T/s1.pm"
check merge_any_order mkpmap -apJ "$T/m.pm" "$T/s2.pm" "$T/s0.pm" "$T/s1.pm"
check merged_is_whole same_body "$T/w.pm" "$T/m.pm"
check_fails missing_shard "shard 1 of 3 is missing" mkpmap -fo -apJ "$T/x.pm" "$T/s0.pm" "$T/s2.pm"
check_fails twice "s0.pm: shard 0 of 3 is given twice" mkpmap -fo -apJ "$T/x.pm" "$T/s0.pm" "$T/s0.pm" "$T/s1.pm" "$T/s2.pm"
check other_seed mk o1.pm -apr 6 -apH 1 3 "$T/box.rad"
check_fails seed_differs "o1.pm: a shard of another run" mkpmap -fo -apJ "$T/x.pm" "$T/s0.pm" "$T/o1.pm" "$T/s2.pm"
check other_count mkpmap -apC "$T/c1.pm" 20k -apo port_m -apr 5 -apH 1 3 "$T/box.rad"
check_fails count_differs "c1.pm: a shard of another run" mkpmap -fo -apJ "$T/x.pm" "$T/s0.pm" "$T/c1.pm" "$T/s2.pm"
check other_scene mk e1.pm -apr 5 -apH 1 3 "$T/box2.rad"
check_fails scene_differs "e1.pm: a shard of another run" mkpmap -fo -apJ "$T/x.pm" "$T/s0.pm" "$T/e1.pm" "$T/s2.pm"
check other_split mk h1.pm -apr 5 -apH 1 2 "$T/box.rad"
check_fails split_differs "h1.pm: shard 1 of 2, .*s0.pm is a shard of 3" mkpmap -fo -apJ "$T/x.pm" "$T/s0.pm" "$T/h1.pm" "$T/s2.pm"
check_fails whole_with_shards "w.pm: not a shard" mkpmap -fo -apJ "$T/x.pm" "$T/s0.pm" "$T/w.pm"
if [ ! -e "$T/x.pm" ]; then pass no_output_on_refusal; else fail no_output_on_refusal "x.pm was written"; fi
