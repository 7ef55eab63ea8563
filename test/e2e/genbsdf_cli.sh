# genBSDF end to end: outputs load in checkBSDF, thread-count independence,
# tensor trees of both ranks, and clear errors for bad input.
. test/e2e/lib.sh

cat > "$T/pane.rad" <<'RAD'
void glass clear 0 0 3 0.96 0.96 0.96
clear polygon pane 0 0 12  -1000 -1000 -2  1000 -1000 -2  1000 1000 -2  -1000 1000 -2
RAD
cat > "$T/sheet.rad" <<'RAD'
void trans sheet 0 0 7 0.6 0.6 0.6 0.05 0.05 0.5 0.3
sheet polygon p 0 0 12  -1000 -1000 -2  1000 -1000 -2  1000 1000 -2  -1000 1000 -2
RAD
DIM="-dim -50 50 -50 50 -4 0"

# Klems, both sides: four blocks, Klems_Full
if genBSDF -c 100 +f +b -geom millimeter $DIM "$T/pane.rad" > "$T/pane.xml" 2> "$T/err" &&
   checkBSDF "$T/pane.xml" > "$T/pane.chk" 2>&1 &&
   grep -q 'Type: Klems_Full' "$T/pane.chk" &&
   [ "$(grep -c '<WavelengthDataDirection>' "$T/pane.xml")" = 4 ]; then pass klems_four_blocks
else fail klems_four_blocks "$(cat "$T/err" "$T/pane.chk" 2>/dev/null | head -5 | tr '\n' ' ')"; fi

# the default is backward only (2 blocks); thread count does not change the
# output (with the default diffuse splitting, -ad 700, as Radiance's genBSDF)
genBSDF -c 16 -n 1 -geom millimeter $DIM "$T/sheet.rad" > "$T/n1.xml" 2>/dev/null
genBSDF -c 16 -n 2 -geom millimeter $DIM "$T/sheet.rad" > "$T/n2.xml" 2>/dev/null
grep -v '^<!--' "$T/n1.xml" > "$T/n1.body"; grep -v '^<!--' "$T/n2.xml" > "$T/n2.body"
if [ -s "$T/n1.xml" ] && cmp -s "$T/n1.body" "$T/n2.body" &&
   [ "$(grep -c '<WavelengthDataDirection>' "$T/n1.xml")" = 2 ]; then pass threads_identical
else fail threads_identical; fi

# tensor trees (-ad 16: the layout is under test, not the default's cost)
if genBSDF -c 50 -r '-ad 16' -t4 3 +f -geom millimeter $DIM "$T/sheet.rad" > "$T/t4.xml" 2>/dev/null &&
   checkBSDF "$T/t4.xml" 2>&1 | grep -q 'Anisotropic_Tensor_Tree' &&
   grep -q '<IncidentDataStructure>TensorTree4' "$T/t4.xml" &&
   [ "$(grep -c '<WavelengthDataDirection>' "$T/t4.xml")" = 3 ]; then pass tree4
else fail tree4; fi
if genBSDF -c 50 -r '-ad 16' -t3 4 -geom millimeter $DIM "$T/sheet.rad" > "$T/t3.xml" 2>/dev/null &&
   checkBSDF "$T/t3.xml" 2>&1 | grep -q 'Isotropic_Tensor_Tree'; then pass tree3
else fail tree3; fi

# +geom: the polygons go into <Geometry format="MGF">
if genBSDF -c 16 +geom millimeter $DIM "$T/pane.rad" > "$T/geom.xml" 2>/dev/null &&
   grep -q '<MGFblock unit="millimeter">' "$T/geom.xml" && grep -q '^f v0 v1 v2 v3' "$T/geom.xml" &&
   checkBSDF "$T/geom.xml" 2>&1 | grep -q 'Has Geometry: 1'; then pass embed_geom
else fail embed_geom; fi

# bad input
check_fails outside_dim 'outside the -dim z range' genBSDF -c 10 -dim -50 50 -50 50 -1 0 "$T/pane.rad"
: > "$T/empty.rad"
check_fails no_surfaces 'no surfaces' genBSDF -c 10 "$T/empty.rad"
cat > "$T/open.rad" <<'RAD'
void dielectric d 0 0 5 1 1 1 1.5 0
d polygon bottom 0 0 12  -100 -100 -3  -100 100 -3  100 100 -3  100 -100 -3
d polygon top 0 0 12  -100 -100 -1  100 -100 -1  100 100 -1  -100 100 -1
RAD
check_fails open_volume 'not closed' genBSDF -c 10 -dim -50 50 -50 50 -4 0 "$T/open.rad"
check_fails bad_unit 'unknown unit' genBSDF -geom parsec "$T/pane.rad"
check_fails bad_dim 'dim expects 6 numbers' genBSDF -dim 1 2 3 x 5 6 "$T/pane.rad"
check_fails missing_file 'nofile' genBSDF "$T/nofile.rad"
check_fails nothing 'nothing to compute' genBSDF -b "$T/pane.rad"
check_fails mixfunc 'not supported by genBSDF' sh -c "printf 'void mixfunc m 4 void void x .\n0\n0\nm polygon p 0 0 9 0 0 -1 1 0 -1 0 1 -1\n' | genBSDF"
check_fails bad_sample_count 'c expects a sample count' genBSDF -c 0 "$T/pane.rad"
# as Radiance's genBSDF: a device at z >= 0 is refused, a flat one (zmin =
# zmax, no -dim) is sampled, and the thickness written is -zmin
sed 's/ -2\( \|$\)/ 2\1/g' "$T/pane.rad" > "$T/room.rad"
check_fails inside_room 'entirely inside the room' genBSDF -c 4 -geom millimeter "$T/room.rad"
if genBSDF -c 4 -geom millimeter "$T/pane.rad" > "$T/flat.xml" 2> "$T/err" &&
   checkBSDF "$T/flat.xml" 2>&1 | grep -q 'Thickness): 200 x 200 x 0.2 cm'; then pass flat_device
else fail flat_device "$(head -3 "$T/err" | tr '\n' ' ')"; fi
