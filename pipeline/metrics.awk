# Annual sensor metrics from pmcompose -E outputs (heliodon.mk: metrics.csv).
# Files: WEATHER pts.txt illuminance.csv direct.csv.  Variables: da (lux, 300), sda (fraction of
# occupied hours, 0.5), ase (lux, 1000), aseh (hours, 250), udi ("100 300 3000"), occ ("8 18":
# occupied from/to, local standard time, by the record's mid-hour), summary (file).
# Occupied hours are counted in the weather file (night hours count as 0 lx); only daylight hours
# are in the CSVs.  Per point: DA = share of occupied hours with E >= da; UDI bands (fell short
# E < b1, supplementary b1..b2, autonomous b2..b3, exceeded > b3); ASE hours = occupied hours with
# direct-sun-only E >= ase.  sDA = share of points with DA >= sda; ASE = share of points with more
# than aseh ASE hours (IES LM-83 definitions).
BEGIN {
    FS = "[ \t,]+"
    if (da == "") da = 300; if (sda == "") sda = 0.5; if (ase == "") ase = 1000; if (aseh == "") aseh = 250
    if (udi == "") udi = "100 300 3000"; if (occ == "") occ = "8 18"
    split(udi, U, " "); split(occ, O, " ")
}
function occupied(h) { return h >= O[1] && h < O[2] }
FILENAME == ARGV[1] {
    if (FNR == 1) epw = ($0 ~ /^LOCATION/)
    if (!epw && FNR > 6 && NF >= 5 && occupied($3 + 0)) nocc++
    if (epw && FNR > 8) { split($0, e, ","); if (occupied(e[4] - 0.5)) nocc++ }
    next
}
FILENAME == ARGV[2] { np++; PX[np] = $1; PY[np] = $2; PZ[np] = $3; next }
FILENAME == ARGV[3] {
    if (FNR == 1) { if (NF - 4 != np) { print "metrics: " FILENAME ": " NF - 4 " points, " ARGV[2] " has " np > "/dev/stderr"; bad = 1; exit 1 } next }
    if (!occupied($4 + 0)) next
    ndl++
    for (i = 1; i <= np; i++) {
        E = $(4 + i)
        if (E >= da) nda[i]++
        if (E < U[1]) ;
        else if (E < U[2]) us[i]++
        else if (E <= U[3]) ua[i]++
        else ue[i]++
    }
    next
}
FILENAME == ARGV[4] {
    if (FNR == 1) next
    if (!occupied($4 + 0)) next
    for (i = 1; i <= np; i++) if ($(4 + i) >= ase) nase[i]++
}
END {
    if (bad) exit 1
    if (nocc < 1) nocc = 1
    print "point,x,y,z,DA,UDI_fell_short,UDI_supplementary,UDI_autonomous,UDI_exceeded,ASE_hours"
    for (i = 1; i <= np; i++) {
        d = nda[i] / nocc; s = us[i] / nocc; a = ua[i] / nocc; x = ue[i] / nocc; f = 1 - s - a - x
        printf "%d,%s,%s,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%d\n", i, PX[i], PY[i], PZ[i], d, f, s, a, x, nase[i] + 0
        if (d >= sda) nsda++
        if (nase[i] + 0 > aseh) nasep++
        sd += d; sf += f; ss += s; sa += a; sx += x
    }
    if (summary != "") {
        printf "points: %d\noccupied_hours: %d (%s-%s h)\ndaylight_occupied_hours: %d\n", np, nocc, O[1], O[2], ndl > summary
        printf "sDA_%s_%d%%: %.1f %%\n", da, sda * 100, 100 * nsda / np > summary
        printf "ASE_%s_%dh: %.1f %%\n", ase, aseh, 100 * nasep / np > summary
        printf "mean_DA_%s: %.1f %%\n", da, 100 * sd / np > summary
        printf "mean_UDI: fell short %.1f %%, supplementary %.1f %%, autonomous %.1f %%, exceeded %.1f %% (bands %s lx)\n", 100 * sf / np, 100 * ss / np, 100 * sa / np, 100 * sx / np, udi > summary
    }
}
