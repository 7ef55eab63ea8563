# ttree_expand.awk -v D=3|4 -v G=log2res : expand a curly-brace tensor tree
# (rttree_reduce / XML <ScatteringData> body) into the full grid, one value
# per line, dimension 0 slowest.  A node is either a list of one value (the
# whole region), of 2^D values (its children; dimension 0 the most
# significant bit of the position) or of 2^D child nodes (dimension 0 the
# least significant bit, as Radiance writes them).
function fill(c, s, v,   n, i, k, idx) {
    n = 1; for (i = 0; i < D; i++) n *= s
    for (k = 0; k < n; k++) {
        idx = 0
        for (i = 0; i < D; i++) idx = idx * R + c[i] + int(k / (s ^ (D - 1 - i))) % s
        val[idx] = v
    }
}
function node(c, s,   vals, nv, i, j, cc, h) {
    if (tok[p] != "{") { print "expected { at token " p > "/dev/stderr"; exit 2 }
    p++
    if (tok[p] == "{") {
        h = s / 2
        for (i = 0; i < 2 ^ D; i++) {
            for (j = 0; j < D; j++) cc[j] = c[j] + int(i / 2 ^ j) % 2 * h
            node(cc, h)
        }
    } else {
        nv = 0
        while (tok[p] != "}") vals[nv++] = tok[p++]
        if (nv == 1) fill(c, s, vals[0])
        else if (nv == 2 ^ D) {
            h = s / 2
            for (i = 0; i < nv; i++) {
                for (j = 0; j < D; j++) cc[j] = c[j] + int(i / 2 ^ (D - 1 - j)) % 2 * h
                fill(cc, h, vals[i])
            }
        } else { print "bad value count " nv > "/dev/stderr"; exit 2 }
    }
    if (tok[p] != "}") { print "expected } at token " p > "/dev/stderr"; exit 2 }
    p++
}
{ gsub(/{/, " { "); gsub(/}/, " } "); for (i = 1; i <= NF; i++) tok[++nt] = $i }
END { R = 2 ^ G; p = 1; for (i = 0; i < D; i++) c0[i] = 0; node(c0, R)
      n = R ^ D; for (k = 0; k < n; k++) printf "%.6g\n", val[k] }
