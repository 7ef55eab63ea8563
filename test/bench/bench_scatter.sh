#!/bin/bash
# Photon tracing through the shared scattering core (scatter.c): stored
# photons per CPU-second of mkpmap -n 1, a glazed roof opening and a
# Lambertian Klems BSDF opening in a black box with a grey floor (2 suns),
# and callgrind instruction counts of the tracing part when valgrind is
# present (BENCH_CALLGRIND=1).
# usage: test/bench/bench_scatter.sh [BUILD]   (prints the figures)
set -e
BUILD=${1:-build}
BIN=$(cd "$BUILD/bin" && pwd)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
N=${N:-1m}
box() {   # $1 = port material line(s) (modifier port_m); geometry: test/e2e/roofbox.rad
    printf 'void plastic black 0 0 5 0 0 0 0 0\nvoid plastic floormat 0 0 5 .5 .5 .5 0 0\n%s\n' "$1"
    printf 'void light solar1 0 0 3 1e6 1e6 1e6\nsolar1 source sun1 0 0 4 0 0 1 0.533\n'
    printf 'void light solar2 0 0 3 1e6 1e6 1e6\nsolar2 source sun2 0 0 4 0.3 0 1 0.533\n'
    cat test/e2e/roofbox.rad
}
# Lambertian Klems (tau 0.5): every element tau/pi
awk 'BEGIN { pi = 3.14159265358979; n = 145
  print "<?xml version=\"1.0\"?><WindowElement xmlns=\"http://windows.lbl.gov\"><WindowElementType>System</WindowElementType><FileType>BSDF</FileType>"
  print "<Optical><Layer><Material><Name>l</Name><Manufacturer>b</Manufacturer><Thickness unit=\"Millimeter\">1</Thickness></Material>"
  print "<DataDefinition><IncidentDataStructure>Columns</IncidentDataStructure><AngleBasis><AngleBasisName>LBNL/Klems Full</AngleBasisName>"
  split("0 10 20 30 40 50 60 70 82.5", th, " "); split("1 8 16 20 24 24 24 16 12", np, " "); split("0 5 15 25 35 45 55 65 75 90", tb, " ")
  for (i = 1; i <= 9; i++) printf "<AngleBasisBlock><Theta>%s</Theta><nPhis>%s</nPhis><ThetaBounds><LowerTheta>%s</LowerTheta><UpperTheta>%s</UpperTheta></ThetaBounds></AngleBasisBlock>\n", th[i], np[i], tb[i], tb[i+1]
  print "</AngleBasis></DataDefinition><WavelengthData><LayerNumber>System</LayerNumber><Wavelength unit=\"Integral\">Visible</Wavelength>"
  print "<WavelengthDataBlock><WavelengthDataDirection>Transmission Front</WavelengthDataDirection><ColumnAngleBasis>LBNL/Klems Full</ColumnAngleBasis><RowAngleBasis>LBNL/Klems Full</RowAngleBasis><ScatteringDataType>BTDF</ScatteringDataType><ScatteringData>"
  for (r = 0; r < n; r++) { l = ""; for (c = 0; c < n; c++) l = l sprintf("%.6f ", 0.5 / pi); print l }
  print "</ScatteringData></WavelengthDataBlock></WavelengthData></Layer></Optical></WindowElement>" }' > "$W/lam.xml"
box "void glass port_m 0 0 3 .96 .96 .96" > "$W/glass.rad"
box "void BSDF port_m 6 0 $W/lam.xml 0 1 0 . 0 0" > "$W/bsdf.rad"
for s in glass bsdf; do
    /usr/bin/time -f "%U %S %e" -o "$W/t" "$BIN/mkpmap" -apC "$W/$s.pm" "$N" -apo port_m -apr 3 -n 1 "$W/$s.rad"
    stored=$("$BIN/pmapdump" "$W/$s.pm" | awk '$1 == "photons" {print $2}')
    read -r u y e < "$W/t"
    awk -v s="$stored" -v u="$u" -v y="$y" -v e="$e" -v n="$s" \
        'BEGIN { printf "mkpmap -n 1 %-5s port: %d stored, %.2f s CPU (%.2f wall): %.2f M stored photons per CPU-second\n", n, s, u + y, e, s / (u + y) / 1e6 }'
    if [ "${BENCH_CALLGRIND:-0}" = 1 ] && command -v valgrind > /dev/null; then
        valgrind --tool=callgrind --callgrind-out-file="$W/cg.$s" "$BIN/mkpmap" -apC "$W/cg_$s.pm" 200k -apo port_m -apr 3 -n 1 "$W/$s.rad" 2>/dev/null
        callgrind_annotate --inclusive=yes "$W/cg.$s" 2>/dev/null |
            awk -v n="$s" '/PROGRAM TOTALS/ { t = $1 } /pmap_build.c:run_batch / && !r { r = $1 }
                END { gsub(",", "", t); gsub(",", "", r); printf "  callgrind 200k %s: %.0f instructions per stored photon in total, %.0f in photon tracing\n", n, t / 200000, r / 200000 }'
    fi
done
