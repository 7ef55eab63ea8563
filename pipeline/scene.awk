# heliodon pipeline: split a Radiance scene stream (comments allowed, !commands already expanded
# by xform) into primitives, one per output line "mod type id nS s.. nI i.. nR r..".
# Variables:
#   mode   room   : everything but the window groups' surfaces (modifier in `mods`), the exterior
#                   ground (modifier in `ground`) and any definition of a group modifier
#          ground : only the surfaces whose modifier is in `ground`
#          win    : only the window groups' surfaces (modifier in `mods`)
#          sel    : only the surfaces of modifier `mod`, their modifier replaced by `newmod`
#          count  : print "modifier count" for every modifier in `mods` (preflight)
#   mods, ground : space-separated modifier names;  mod, newmod : for mode sel
#   name   : file name for messages
function want(m, t, id) {
    if (mode == "room") return !((m in G) || (m in W) || (m == "void" && (id in G)))
    if (mode == "ground") return (m in W)
    if (mode == "win" || mode == "count") return (m in G)
    if (mode == "sel") return m == mod
    return 0
}
function fail(msg) { printf "heliodon-pipeline: %s: %s\n", name, msg > "/dev/stderr"; bad = 1; exit 1 }
BEGIN {
    n = split(mods, a, " "); for (i = 1; i <= n; i++) G[a[i]] = 1
    n = split(ground, a, " "); for (i = 1; i <= n; i++) W[a[i]] = 1
    if (name == "") name = "scene"
    nt = 0
}
/^[ \t]*#/ { next }
{ for (i = 1; i <= NF; i++) tok[nt++] = $i }
END {
    if (bad) exit 1
    p = 0
    while (p < nt) {
        if (p + 3 > nt) fail("truncated primitive at token " p)
        m = tok[p]; t = tok[p + 1]; id = tok[p + 2]; q = p + 3
        if (t == "alias") {
            if (q >= nt) fail("alias " id ": missing reference")
            out = m " " t " " id " " tok[q]; q++
        } else {
            out = ""
            for (k = 0; k < 3; k++) {
                if (q >= nt || tok[q] !~ /^[0-9]+$/) fail("primitive " m " " t " " id ": expected an argument count at token " q)
                c = tok[q] + 0
                if (q + c >= nt) fail("primitive " m " " t " " id ": arguments run past the end")
                s = c; for (j = 1; j <= c; j++) s = s " " tok[q + j]
                out = out " " s; q += c + 1
            }
            out = m " " t " " id out
        }
        if (want(m, t, id)) {
            if (mode == "count") cnt[m]++
            else if (mode == "sel") { sub(/^[^ ]+/, newmod, out); print out }
            else print out
        }
        p = q
    }
    if (mode == "count") for (x in G) print x, cnt[x] + 0
}
