# klems_err.awk: accuracy of a Klems-full T (or R) matrix against a reference.
#   awk -f klems_err.awk ours.mtx ref.mtx
# Both files are rmtxop -fa ascii output of an LBNL Klems-full XML: 145 rows
# (outgoing patches) x 145 columns (incident patches) x NCOMP, element
# f(o,i) * lambda(i), where lambda is the patch's projected solid angle.
# Prints four percentages:
#   mean   mean over incident patches of |T_ours(i) - T_ref(i)| / T_ref(i)
#   inner  the largest such difference among patches 0-132 (theta < 75 deg)
#   ring   the largest among patches 133-144 (the grazing ring, 75-90 deg)
#   elem   mean |ours - ref| / ref over the elements whose reference exceeds
#          1 % of its row maximum
# where T(i) = sum_o f(o,i) lambda(o) is the directional-hemispherical
# value for incident patch i (patches with T_ref < 1e-4 are skipped).
BEGIN {
    split("0 5 15 25 35 45 55 65 75 90", tb, " ")
    split("1 8 16 20 24 24 24 16 12", np, " ")
    n = 0
    for (r = 1; r <= 9; r++) {
        c0 = cos(tb[r] * 3.14159265358979 / 180); c1 = (r == 9) ? 0 : cos(tb[r + 1] * 3.14159265358979 / 180)
        for (k = 0; k < np[r]; k++) lam[n++] = 3.14159265358979 * (c0 * c0 - c1 * c1) / np[r]
    }
}
FNR == 1 { f++; hdr = 1; row = 0 }
hdr { if ($0 ~ /^NCOMP=/) { split($0, q, "="); nc[f] = q[2] } if ($0 == "") hdr = 0; next }
NF {
    if (NF != 145 * nc[f]) { printf "%s: line %d: expected %d numbers, found %d\n", FILENAME, FNR, 145 * nc[f], NF > "/dev/stderr"; bad = 1; exit 1 }
    for (i = 0; i < 145; i++) v[f, row, i] = $(i * nc[f] + 1 + (nc[f] > 1))
    row++; nrow[f] = row
}
END {
    if (bad) exit 1
    if (nrow[1] != 145 || nrow[2] != 145) { printf "expected 145 rows, found %d and %d\n", nrow[1], nrow[2] > "/dev/stderr"; exit 1 }
    for (i = 0; i < 145; i++) {
        a = b = 0
        for (o = 0; o < 145; o++) { a += v[1, o, i] / lam[i] * lam[o]; b += v[2, o, i] / lam[i] * lam[o] }
        if (b < 1e-4) continue
        d = (a - b) / b; if (d < 0) d = -d
        sm += d; ns++
        if (i < 133) { if (d > mi) mi = d } else if (d > mr) mr = d
    }
    for (o = 0; o < 145; o++) {
        rm = 0
        for (i = 0; i < 145; i++) if (v[2, o, i] > rm) rm = v[2, o, i]
        for (i = 0; i < 145; i++) {
            w = v[2, o, i]
            if (w > 0.01 * rm && w > 0) { d = (v[1, o, i] - w) / w; if (d < 0) d = -d; el += d; ne++ }
        }
    }
    printf "%.3f %.3f %.3f %.3f\n", 100 * sm / ns, 100 * mi, 100 * mr, 100 * el / ne
}
