# Piecewise-linear fit of one palette channel sampled by probe.sh.
# Input: samples_<pal>.txt (v red green blue); -v col=2|3|4, -v tol=...
# Greedy: each segment runs from the previous knot to the furthest sample
# such that the chord between the two samples stays within tol of every
# sample between them.  Output: one knot per line, "v value".
{ x[NR - 1] = $1; y[NR - 1] = $col }
END {
    n = NR - 1; i = 0
    printf "%.9g %.9g\n", x[0], y[0]
    while (i < n) {
        j = i + 1
        while (j + 1 <= n && fits(i, j + 1)) j++
        printf "%.9g %.9g\n", x[j], y[j]
        i = j
    }
}
function fits(a, b,    k, t, d) {
    for (k = a + 1; k < b; k++) {
        t = y[a] + (y[b] - y[a]) * (x[k] - x[a]) / (x[b] - x[a])
        d = t - y[k]; if (d < 0) d = -d
        if (d > tol) return 0
    }
    return 1
}
