#!/bin/bash
# Newer Radiance names scripts call: rxcontrib / rxfluxmtx (the same programs
# as rcontrib / rfluxmtx), dctimestep -m (accepted), gendaymtx reading an
# EPW file directly.
. test/e2e/lib.sh
B=$REF/scenes/box
if ! have_ref scenes/box; then skip newer_names "no reference folder $REF"; exit 0; fi
T=$(cd "$T" && pwd)

# rxcontrib = rcontrib (direct sun, deterministic)
RC="-h -I+ -ab 0 -dj 0 -st 0 -lr 12 -m solar $B/box_room.rad $B/box_window.rad $B/sun_clear_0101_1030.rad"
rcontrib $RC < "$B/sensors.pts" > "$T/rc.dat" 2>"$T/err" || fail rcontrib "$(cat "$T/err")"
rxcontrib $RC < "$B/sensors.pts" > "$T/rxc.dat" 2>"$T/err" || fail rxcontrib_runs "$(cat "$T/err")"
if [ -s "$T/rc.dat" ] && [ "$(awk '$1>0' "$T/rc.dat" | wc -l)" -ge 5 ] && cmp -s "$T/rc.dat" "$T/rxc.dat"; then pass rxcontrib_same_as_rcontrib
else fail rxcontrib_same_as_rcontrib "$(diff "$T/rc.dat" "$T/rxc.dat" | head -2 | tr '\n' ' ')"; fi
check_fails rxcontrib_usage "modifier|usage|-m" rxcontrib "$B/box_room.rad"

# rxfluxmtx = rfluxmtx (window to sky patches, fixed seed by -c 1 -ab 0 direct)
rfluxmtx -h -ff -c 2 -ab 1 -ad 16 -lw 1e-3 "$B/window_tx.rad" "$B/sky_rx.rad" "$B/box_room.rad" > "$T/f.dmx" 2>"$T/err" || fail rfluxmtx "$(cat "$T/err")"
rxfluxmtx -h -ff -c 2 -ab 1 -ad 16 -lw 1e-3 "$B/window_tx.rad" "$B/sky_rx.rad" "$B/box_room.rad" > "$T/rxf.dmx" 2>"$T/err" || fail rxfluxmtx_runs "$(cat "$T/err")"
if [ -s "$T/f.dmx" ] && cmp -s "$T/f.dmx" "$T/rxf.dmx"; then pass rxfluxmtx_same_as_rfluxmtx
else fail rxfluxmtx_same_as_rfluxmtx "sizes $(wc -c < "$T/f.dmx") $(wc -c < "$T/rxf.dmx")"; fi

# dctimestep -m GB -N n: accepted, same result
dctimestep "$B/a4_dc/sens_mf1_direct_ab0.dc" "$B/a4_sunvec_mf1_0101_1030_noground.vec" > "$T/d1.dat" 2>"$T/err" || fail dctimestep "$(cat "$T/err")"
dctimestep -m 2 -N 1 "$B/a4_dc/sens_mf1_direct_ab0.dc" "$B/a4_sunvec_mf1_0101_1030_noground.vec" > "$T/d2.dat" 2>"$T/err" || fail dctimestep_m "$(cat "$T/err")"
if [ -s "$T/d1.dat" ] && cmp -s <(getinfo - < "$T/d1.dat") <(getinfo - < "$T/d2.dat"); then pass dctimestep_m_N
else fail dctimestep_m_N "results differ"; fi

# gendaymtx on an EPW file directly: one column per hour of the 3 days
# 146 patches x 72 hours
if [ -f "$B/chicago_0101-0103.epw" ]; then
    gendaymtx -h -m 1 "$B/chicago_0101-0103.epw" > "$T/epw.smx" 2>"$T/err" || fail gendaymtx_epw "$(cat "$T/err")"
    cols=$(awk 'NF==3' "$T/epw.smx" | wc -l)
    if [ "$cols" -eq $((146 * 72)) ]; then pass gendaymtx_epw_size; else fail gendaymtx_epw_size "$cols values"; fi
fi
