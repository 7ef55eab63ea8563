# Rays from stratified points of the window groups' polygons (win.rad: one primitive per line, as
# scene.awk writes them), cosine-distributed about both sides of each polygon, for finding the
# exterior ground the windows see (heliodon.mk: groundpts.txt).  n = rays in all (default 1024),
# shared by area; seed (default 1).  Output "x y z dx dy dz"; origins 1 mm off the surface.
function rnd() { return rand() }
BEGIN { if (n == "") n = 1024; srand(seed == "" ? 1 : seed); pi = 3.14159265358979 }
$2 == "polygon" {
    k = 4; ns = $(k) + 0; k += ns + 1; ni = $(k) + 0; k += ni + 1; nr = $(k) + 0
    nv = int(nr / 3); if (nv < 3) next
    np++
    for (v = 0; v < nv; v++) { X[np, v] = $(k + 1 + 3 * v); Y[np, v] = $(k + 2 + 3 * v); Z[np, v] = $(k + 3 + 3 * v) }
    NV[np] = nv
    # Newell normal and fan triangles
    nx = ny = nz = 0
    for (v = 0; v < nv; v++) { w = (v + 1) % nv
        nx += (Y[np, v] - Y[np, w]) * (Z[np, v] + Z[np, w]); ny += (Z[np, v] - Z[np, w]) * (X[np, v] + X[np, w]); nz += (X[np, v] - X[np, w]) * (Y[np, v] + Y[np, w]) }
    l = sqrt(nx * nx + ny * ny + nz * nz); if (l == 0) { np--; next }
    NX[np] = nx / l; NY[np] = ny / l; NZ[np] = nz / l; A[np] = l / 2; atot += l / 2
}
END {
    if (np == 0) exit 0
    g = int(sqrt(n)); if (g < 1) g = 1
    for (p = 1; p <= np; p++) {
        m = int(n * A[p] / atot + 0.5); if (m < 2) m = 2
        # tangent frame
        if (NZ[p] > 0.9 || NZ[p] < -0.9) { ux = 1; uy = 0; uz = 0 } else { ux = 0; uy = 0; uz = 1 }
        tx = uy * NZ[p] - uz * NY[p]; ty = uz * NX[p] - ux * NZ[p]; tz = ux * NY[p] - uy * NX[p]
        l = sqrt(tx * tx + ty * ty + tz * tz); tx /= l; ty /= l; tz /= l
        bx = NY[p] * tz - NZ[p] * ty; by = NZ[p] * tx - NX[p] * tz; bz = NX[p] * ty - NY[p] * tx
        gm = int(sqrt(m)); if (gm < 1) gm = 1
        for (i = 0; i < m; i++) {
            # point: a fan triangle by area, uniform inside
            r = rnd() * A[p]; acc = 0
            for (v = 1; v < NV[p] - 1; v++) {
                ax = X[p, v] - X[p, 0]; ay = Y[p, v] - Y[p, 0]; az = Z[p, v] - Z[p, 0]
                cx = X[p, v + 1] - X[p, 0]; cy = Y[p, v + 1] - Y[p, 0]; cz = Z[p, v + 1] - Z[p, 0]
                qx = ay * cz - az * cy; qy = az * cx - ax * cz; qz = ax * cy - ay * cx
                acc += sqrt(qx * qx + qy * qy + qz * qz) / 2
                if (r <= acc || v == NV[p] - 2) break
            }
            s = rnd(); t = rnd(); if (s + t > 1) { s = 1 - s; t = 1 - t }
            px = X[p, 0] + s * ax + t * cx; py = Y[p, 0] + s * ay + t * cy; pz = Z[p, 0] + s * az + t * cz
            u1 = ((i % gm) + rnd()) / gm; u2 = (int(i / gm) % gm + rnd()) / gm
            rr = sqrt(u1); ph = 2 * pi * u2; h = sqrt(1 - u1)
            side = (i % 2) ? 1 : -1
            dx = rr * cos(ph) * tx + rr * sin(ph) * bx + side * h * NX[p]
            dy = rr * cos(ph) * ty + rr * sin(ph) * by + side * h * NY[p]
            dz = rr * cos(ph) * tz + rr * sin(ph) * bz + side * h * NZ[p]
            printf "%.5f %.5f %.5f %.6f %.6f %.6f\n", px + 0.001 * side * NX[p], py + 0.001 * side * NY[p], pz + 0.001 * side * NZ[p], dx, dy, dz
        }
    }
}
