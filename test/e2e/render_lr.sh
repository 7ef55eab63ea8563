#!/bin/bash
# -lr counts reflected rays only, as Radiance's rayorigin (walk.c child):
# a view ray through three glass panes (transmitted rays, not counted) to a
# glow, -ab 0, deterministic.  With -lr 1 Radiance sees the glow through
# the three panes plus nothing reflected; -lr 2 adds the light reflected
# twice between the panes, -lr 4 four times; -lr -2 / -4 (roulette with
# the same upper limit, -lw 1e-6: no ray is below it).  heliodon's rtrace
# and rcontrib (the glow's coefficient × its radiance 10) must give
# Radiance 6.1's values (test/data/render_lr, commands in MANIFEST.md) to
# 1e-5.  Counting the transmitted rays too gives 0 for -lr 1 and 2.
. test/e2e/lib.sh
D=test/data/render_lr
while read -r lr ref; do
    h=$(echo 0 0 0 0 0 1 | rtrace -h -ab 0 -lr $lr -lw 1e-6 "$D/panes.rad" 2>"$T/err" | awk '{print $1}')
    k=$(echo 0 0 0 0 0 1 | rcontrib -h -ab 0 -lr $lr -lw 1e-6 -m lamp "$D/panes.rad" 2>>"$T/err" | awk '{print 10 * $1}')
    if [ -n "$h" ] && close "$h" "$ref" 1e-5; then pass "lr${lr}_rtrace"
    else fail "lr${lr}_rtrace" "heliodon $h, Radiance $ref $(head -c 200 "$T/err")"; fi
    if [ -n "$k" ] && close "$k" "$ref" 1e-5; then pass "lr${lr}_rcontrib"
    else fail "lr${lr}_rcontrib" "heliodon $k, Radiance $ref $(head -c 200 "$T/err")"; fi
done < "$D/radiance_lr.txt"
