# Shared helpers for end-to-end tests (sourced).  Programs are on PATH
# (build/bin first); HELIODON_REF points at the reference folder.
# Report with pass/fail/skip; each prints one line that run-tests.sh counts.
set -u
T=${HD_TEST_TMP:-build/tmp}/e2e.$(basename "$0" .sh)
rm -rf "$T"; mkdir -p "$T"
REF=${HELIODON_REF:-../shared/ref}
# absolute, so that scripts may cd or link into their temporary folders
[ -d "$REF" ] && REF=$(cd "$REF" && pwd)
pass() { echo "PASS: $(basename "$0"):$1"; }
fail() { echo "FAIL: $(basename "$0"):$1${2:+: $2}"; }
skip() { echo "SKIP: $(basename "$0"):$1: $2"; }
# check NAME COMMAND... : pass if the command succeeds
check() { n=$1; shift; if "$@" >"$T/check.out" 2>&1; then pass "$n"; else fail "$n" "$(tail -3 "$T/check.out" | tr '\n' ' ')"; fi; }
# check_fails NAME PATTERN COMMAND... : the command must exit non-zero and
# print PATTERN (grep -E) on stderr/stdout
check_fails() {
    n=$1; pat=$2; shift 2
    if "$@" >"$T/check.out" 2>&1; then fail "$n" "succeeded unexpectedly"
    elif grep -Eq -e "$pat" "$T/check.out"; then pass "$n"
    else fail "$n" "message did not match '$pat': $(head -3 "$T/check.out" | tr '\n' ' ')"; fi
}
# close A B RTOL : |A-B| <= RTOL*|B|
close() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN{d=a-b; if(d<0)d=-d; m=b<0?-b:b; exit !(d<=t*m)}'; }
have_ref() { [ -d "$REF/$1" ]; }
# data_values FILE : print the numbers after the information header (ascii)
data_values() { awk 'hdr==0 && /^$/ {hdr=1; next} hdr==1 {for(i=1;i<=NF;i++) print $i}' "$1"; }
# maxrel A B FLOOR : max |a-b|/|b| over paired values with |b| > FLOOR
#   (prints the value; exit 1 if the counts differ)
maxrel() {
    data_values "$1" > "$T/maxrel.a"; data_values "$2" > "$T/maxrel.b"
    awk -v floor="$3" 'NR==FNR {a[NR]=$1; na=NR; next}
        {nb=FNR; b=$1; d=a[FNR]-b; if(d<0)d=-d; m=b<0?-b:b; if(m>floor && d/m>mx) mx=d/m}
        END {if (na!=nb) {print "count " na " vs " nb; exit 1} printf "%.3g\n", mx+0}' "$T/maxrel.a" "$T/maxrel.b"
}
# le A B : A <= B numerically
le() { awk -v a="$1" -v b="$2" 'BEGIN{exit !(a<=b)}'; }
# lambert_xml TAU FILE : a Klems-full LBNL XML whose Transmission Front is
# Lambertian (every element TAU/pi, no reflection)
lambert_xml() {
    awk -v tau="$1" 'BEGIN {
        pi = 3.14159265358979
        nt = split("0 10 20 30 40 50 60 70 82.5", th, " ")
        split("1 8 16 20 24 24 24 16 12", np, " ")
        split("0 5 15 25 35 45 55 65 75 90", tb, " ")
        print "<?xml version=\"1.0\" encoding=\"UTF-8\"?>"
        print "<WindowElement xmlns=\"http://windows.lbl.gov\">"
        print "<WindowElementType>System</WindowElementType><FileType>BSDF</FileType>"
        print "<Optical><Layer><Material><Name>lambert</Name><Manufacturer>test</Manufacturer>"
        print "<Thickness unit=\"Millimeter\">1</Thickness></Material>"
        print "<DataDefinition><IncidentDataStructure>Columns</IncidentDataStructure>"
        print "<AngleBasis><AngleBasisName>LBNL/Klems Full</AngleBasisName>"
        n = 0
        for (i = 1; i <= nt; i++) {
            printf "<AngleBasisBlock><Theta>%s</Theta><nPhis>%s</nPhis><ThetaBounds><LowerTheta>%s</LowerTheta><UpperTheta>%s</UpperTheta></ThetaBounds></AngleBasisBlock>\n", th[i], np[i], tb[i], tb[i+1]
            n += np[i]
        }
        print "</AngleBasis></DataDefinition>"
        print "<WavelengthData><LayerNumber>System</LayerNumber><Wavelength unit=\"Integral\">Visible</Wavelength>"
        print "<WavelengthDataBlock><WavelengthDataDirection>Transmission Front</WavelengthDataDirection>"
        print "<ColumnAngleBasis>LBNL/Klems Full</ColumnAngleBasis><RowAngleBasis>LBNL/Klems Full</RowAngleBasis>"
        print "<ScatteringDataType>BTDF</ScatteringDataType><ScatteringData>"
        v = tau / pi
        for (r = 0; r < n; r++) { line = ""; for (c = 0; c < n; c++) line = line sprintf("%.6f ", v); print line }
        print "</ScatteringData></WavelengthDataBlock></WavelengthData></Layer></Optical></WindowElement>"
    }' > "$2"
}
# ---- the office pipeline's site and references (pipeline_*.sh) ----
# izmir_wea FILE RECORD... : a WEA file of the Izmir-like site the office
#   pipeline tests use; each RECORD is "month day hour DNI DHI"
izmir_wea() {
    f=$1; shift
    printf '%s\n' "place Izmir_e2e" "latitude 38.4" "longitude -27.1" "time_zone -30" "site_elevation 25" \
        "weather_data_file_units 1" "$@" > "$f"
}
# izmir_sky FILE MONTH DAY HOUR DNI DHI : that site's Perez sky without its
#   sun (gendaylit -s), for a reference rendering with the patch-centre sun
izmir_sky() { gendaylit "$2" "$3" "$4" -a 38.4 -o -27.1 -m -30 -W "$5" "$6" -s > "$1"; }
# patchsun_rad FILE R G B DX DY DZ : a 0.533-degree sun of radiance R G B in
#   direction DX DY DZ (the columns of a pipeline run's hours.log)
patchsun_rad() {
    printf 'void light refsun 0 0 3 %s %s %s\nrefsun source sun 0 0 4 %s %s %s 0.533\n' "$2" "$3" "$4" "$5" "$6" "$7" > "$1"
}
# wea_record WEA MONTH DAY HOUR : the "DNI DHI" of that record of a WEA file
wea_record() { awk -v m="$2" -v d="$3" -v h="$4" 'NR > 6 && $1 == m && $2 == d && $3 + 0 == h + 0 {print $4, $5}' "$1"; }
# meanlum PICTURE : mean luminance (cd/m2, 179 x channel value) of a picture
meanlum() { pvalue -h -H -b -d "$1" | awk '{s += 179 * $1; n++} END {printf "%.6g\n", s / n}'; }
# roofbox_suns : a black box with a glazed roof opening (port_m), a grey floor
# (test/e2e/roofbox.rad) and two suns (solar1 overhead, solar2 tilted)
roofbox_suns() {
    cat <<'EOF'
void plastic black 0 0 5 0 0 0 0 0
void plastic floormat 0 0 5 .5 .5 .5 0 0
void glass port_m 0 0 3 .96 .96 .96
void light solar1 0 0 3 1e6 1e6 1e6
solar1 source sun1 0 0 4 0 0 1 0.533
void light solar2 0 0 3 1e6 1e6 1e6
solar2 source sun2 0 0 4 0.3 0 1 0.533
EOF
    cat test/e2e/roofbox.rad
}
# roofbox_coef FACTOR PTS : FACTOR x Omega_sun x F per floor point "x y z ..." of PTS, F the view
# factor from the point to roofbox.rad's 0.5 x 0.5 m opening at z = 1 (exact formula for a
# parallel rectangle): the sun coefficient under a Lambertian opening of transmittance FACTOR
# (times the cosine of the sun's incidence)
roofbox_coef() {
    awk -v k="$1" 'function fc(a, b,   s, X, Y) { s = (a < 0 ? -1 : 1) * (b < 0 ? -1 : 1); X = a < 0 ? -a : a; Y = b < 0 ? -b : b
            return s / (2 * 3.14159265358979) * (X / sqrt(1 + X*X) * atan2(Y, sqrt(1 + X*X)) + Y / sqrt(1 + Y*Y) * atan2(X, sqrt(1 + Y*Y))) }
        { x = $1; y = $2; h = 1 - $3
          F = fc((.75-x)/h, (.75-y)/h) - fc((.25-x)/h, (.75-y)/h) - fc((.75-x)/h, (.25-y)/h) + fc((.25-x)/h, (.25-y)/h)
          om = 2 * 3.14159265358979 * (1 - cos(0.533 / 2 * 3.14159265358979 / 180)); printf "%.6e\n", k * om * F }' "$2"
}
# same_numbers FILE1 FILE2 REL [ABS] : the two text files have the same lines and
# words; numbers may differ by REL relative (to FILE2's) or ABS absolute (default
# 1e-300), other words not.  Prints the first difference and fails.
same_numbers() {
    awk -v rel="$3" -v abs="${4:-1e-300}" '
         function isnum(s) { return s ~ /^[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?$/ }
         NR == FNR { n1++; a[n1] = $0; next }
         { n2++; b[n2] = $0 }
         END {
            if (n1 != n2) { print "lines " n1 " vs " n2; exit 1 }
            for (i = 1; i <= n1; i++) {
                k1 = split(a[i], x); k2 = split(b[i], y)
                if (k1 != k2) { print "line " i ": " a[i] " | " b[i]; exit 1 }
                for (j = 1; j <= k1; j++) {
                    if (x[j] == y[j]) continue
                    if (isnum(x[j]) && isnum(y[j])) {
                        d = x[j] - y[j]; if (d < 0) d = -d
                        m = y[j] < 0 ? -y[j] : y[j]
                        if (d <= rel * m || d < abs) continue
                    }
                    print "line " i ": " x[j] " vs " y[j]; exit 1
                }
            }
         }' "$1" "$2"
}
# radiance_font : succeed when Radiance's font helvet.fnt is found through
#   RAYPATH, or in a Radiance library named by RADIANCE_LIB or
#   RADIANCE_BIN/../lib (then that library is added to RAYPATH); the
#   project ships no font, and text drawn without one is heliodon's own
radiance_font() {
    local d IFS=:
    for d in ${RAYPATH:-.}; do [ -f "${d:-.}/helvet.fnt" ] && return 0; done
    d=${RADIANCE_LIB:-${RADIANCE_BIN:+$RADIANCE_BIN/../lib}}
    if [ -n "$d" ] && [ -f "$d/helvet.fnt" ]; then export RAYPATH="${RAYPATH:-.}:$(cd "$d" && pwd)"; return 0; fi
    return 1
}
