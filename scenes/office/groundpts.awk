# Points of the exterior ground seen from the windows, for the sunlit ground fractions
# (Makefile: groundsun.txt).  Rays start at stratified points of the window band (x 0.1..3.5,
# z 0.1..2.9, y = 0) in cosine-distributed directions of the outer hemisphere (-y); those going
# down are cut with the ground plane (z = 0; room.rad's polygon is 1 mm below); a point behind the
# building opposite's north face (y < -20 within x -18.2..21.8: the face is seen there) or beyond
# the 100 m ground polygon is dropped.  Output: "x y z 0 0 1" lines (rcontrib -I).
# Variables: n (rays, default 1024), seed (default 1).
BEGIN {
    if (n == "") n = 1024
    srand(seed == "" ? 1 : seed)
    g = int(sqrt(n)); if (g < 1) g = 1
    pi = 3.14159265358979
    for (i = 0; i < g * g; i++) {
        x0 = 0.1 + 3.4 * rand(); z0 = 0.1 + 2.8 * rand()
        u1 = ((i % g) + rand()) / g; u2 = (int(i / g) + rand()) / g
        r = sqrt(u1); ph = 2 * pi * u2
        dx = r * cos(ph); dz = r * sin(ph); dy = -sqrt(1 - u1)   # cosine-weighted about -y
        if (dz >= -1e-6) continue
        t = -z0 / dz
        x = x0 + t * dx; y = t * dy
        if (y < -20 && x > -18.2 && x < 21.8) continue
        if (x < -100 || x > 100 || y < -100) continue
        printf "%.4f %.4f 0.001 0 0 1\n", x, y
    }
}
