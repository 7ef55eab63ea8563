# the probe rays of normalmat.rad: towards the centre of each panel from
# above and below (14 directions each, 6 of them about the source's mirror
# and straight-through directions), and towards 6 points of each sphere
function ray(cx, cy, cz, dx, dy, dz,   n) {
    n = sqrt(dx * dx + dy * dy + dz * dz); dx /= n; dy /= n; dz /= n
    printf "%.9f %.9f %.9f %.9f %.9f %.9f\n", cx - 2 * dx, cy - 2 * dy, cz - 2 * dz, dx, dy, dz
}
BEGIN {
    pi = 3.14159265358979; n = split("0 10 25 45 60 75 80 85", th, " ")
    ln = sqrt(.3 * .3 + .2 * .2 + 1); lx = .3 / ln; ly = .2 / ln; lz = 1 / ln
    split("0 .03 0 .1 -.15 .25", ox, " "); split("0 0 .05 .02 .1 -.1", oy, " ")
    for (p = 0; p < 8; p++) {
        cx = 3 * p + 1
        for (s = 1; s >= -1; s -= 2) {
            for (i = 1; i <= n; i++) {
                t = th[i] * pi / 180; f = (37 * i + 90 * p) * pi / 180
                ray(cx, 0, 0, sin(t) * cos(f), sin(t) * sin(f), -s * cos(t))
            }
            for (i = 1; i <= 6; i++) ray(cx, 0, 0, lx + ox[i], ly + oy[i], -s * lz)
        }
    }
    for (b = 0; b < 2; b++)
        for (i = 0; i < 6; i++) {
            t = (20 + 25 * i) * pi / 180; f = (50 * i) * pi / 180
            ray(1 + 4 * b + .5 * sin(t) * cos(f), 20 + .5 * sin(t) * sin(f), .5 * cos(t), -sin(t) * cos(f), -sin(t) * sin(f), -cos(t))
        }
}
