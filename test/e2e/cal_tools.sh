# End-to-end tests of the .cal language and the record programs (rcalc, ev,
# cnt, total, rcollate, histo, rlam, neaten) and of rcontrib's -e/-f/-b/-bn bins against
# Radiance 6.1 (ref/cal: every case with its command in MANIFEST.md and
# out/cases_*.tsv).  Each case runs the recorded command verbatim in a
# scratch folder (inputs/ -> the reference inputs) with heliodon's programs
# and its own library .cal files (lib/), then compares:
#   text output   token by token: numbers within 1e-7 relative (float
#                 printing), other words exactly (CAPDATE=/GMT= header lines
#                 removed, tabfunc's `p<pid> suffixes made equal);
#   binary output byte-exact;
#   stderr        exactly (the calculator's messages), when Radiance wrote one;
#   exit status   equal.
# Cases calling programs heliodon does not have yet are SKIPped by name.
. test/e2e/lib.sh

LIBDIR=$(pwd)/lib
if ! have_ref cal; then skip cal_reference "no $REF/cal"; exit 0; fi
# absolute paths: the cases run in a scratch folder
REF=$(cd "$REF" && pwd)
CAL=$REF/cal

W=$(cd "$T" && pwd)/work
mkdir -p "$W/out"
ln -s "$CAL/inputs" "$W/inputs"
# inputs some cases read from out/ (the direction list, tabfunc's output)
cp "$CAL/out/r21_dirs.txt" "$CAL/out/r28_tabfunc.cal" "$W/out/"

# numbers within 1e-7, words exactly (lib.sh)
same_text() { same_numbers "$1" "$2" 1e-7; }

run_cases() {  # tsv
    while IFS='	' read -r id rc desc cmd; do
        case $id in rc*) continue ;; esac
        missing=
        for prog in pcomb pfilt pextrem falsecolor pcompos pflip protate \
                    getbbox genprism genrev gensurf; do
            case " $cmd " in *"$prog "*) missing="$missing $prog" ;; esac
        done
        if [ -n "$missing" ]; then skip "$id" "needs$missing (not in heliodon yet)"; continue; fi
        ( cd "$W" && RAYPATH=.:$LIBDIR LC_ALL=C bash -o pipefail -c "$cmd" ) 2> "$W/$id.err"
        got=$?
        why=
        [ "$got" = "$rc" ] || why="exit $got, Radiance $rc"
        for ref in "$CAL"/out/"$id".*; do
            f=$(basename "$ref")
            case $f in *.err) continue ;; esac
            if [ ! -f "$W/out/$f" ]; then why="$why; no $f"; continue; fi
            case $f in
            *.bin) cmp -s "$W/out/$f" "$ref" || why="$why; $f differs" ;;
            *)  # the date lines of headers and tabfunc's process-id suffix differ by nature
                norm='/^CAPDATE= /d; /^GMT= /d; s/`p[0-9][0-9]*/`pID/g'
                sed "$norm" "$W/out/$f" > "$W/$f.got"; sed "$norm" "$ref" > "$W/$f.ref"
                d=$(same_text "$W/$f.got" "$W/$f.ref") || why="$why; $f: $d" ;;
            esac
        done
        if [ -f "$CAL/out/$id.err" ]; then
            cmp -s "$W/$id.err" "$CAL/out/$id.err" || why="$why; stderr '$(head -2 "$W/$id.err" | tr '\n' '|')'"
        fi
        if [ -z "$why" ]; then pass "$id"; else fail "$id" "$why"; fi
    done < "$1"
}

run_cases "$CAL/out/cases_rcalc.tsv"
run_cases "$CAL/out/cases_tables.tsv"

# ---- rcontrib bins (Monte Carlo: statistical comparison) ----
# Same scene files as rc00 (heliodon's rcontrib reads them directly).  The
# bin count of each record must be the same; the sum over the bins within
# 15 % per sensor (256 diffuse samples, of which few reach the sky through
# the window: at -ad 16384 both programs agree within 1.5 %) and 3 % over
# all sensors.  The bins themselves are checked exactly by r22-r25 (rcalc
# on the same .cal files) and by test_contrib (.cal bins = built-in bins).
BOXS="$REF/scenes/box/box_room.rad $REF/scenes/box/box_window.rad $CAL/inputs/skyglow_rc.rad"
OPTS='-u- -n 1 -I+ -ab 1 -ad 256 -lw 1e-3'
rc_case() {  # id stdin-file args...
    id=$1 in=$2; shift 2
    if ! rcontrib -h $OPTS "$@" $BOXS < "$in" > "$W/$id.txt" 2> "$W/$id.err"; then
        fail "$id" "rcontrib failed: $(head -2 "$W/$id.err" | tr '\n' ' ')"; return
    fi
    r=$(awk 'NR == FNR { n1[FNR] = NF; for (i = 1; i <= NF; i++) s1[FNR] += $i; next }
             { if (NF != n1[FNR]) { print "fields " n1[FNR] " vs " NF; bad = 1; exit }
               t = 0; for (i = 1; i <= NF; i++) t += $i
               S1 += s1[FNR]; S2 += t
               d = s1[FNR] - t; if (d < 0) d = -d
               if (d > 0.15 * t) { printf "record %d: sum %g vs %g\n", FNR, s1[FNR], t; bad = 1; exit } }
             END { if (!bad && FNR > 1) { d = S1 - S2; if (d < 0) d = -d; if (d > 0.03 * S2) printf "total %g vs %g\n", S1, S2 } }' \
         "$W/$id.txt" "$CAL/out/$id.txt")
    if [ -n "$r" ]; then fail "$id" "$r"; return; fi
    if [ -f "$CAL/out/$id.err" ] && ! cmp -s "$W/$id.err" "$CAL/out/$id.err"; then
        fail "$id" "stderr '$(cat "$W/$id.err")' vs '$(cat "$CAL/out/$id.err")'"; return
    fi
    pass "$id"
}
( cd "$W" && RAYPATH=.:$LIBDIR rc_case rc01_mf2_before inputs/sensors_rc.pts -e MF:2 -f reinhartb.cal -b rbin -bn Nrbins -m sky_glow )
( cd "$W" && RAYPATH=.:$LIBDIR rc_case rc02_mf2_after inputs/sensors_rc.pts -f reinhartb.cal -e MF:2 -b rbin -bn Nrbins -m sky_glow )
( cd "$W" && RAYPATH=.:$LIBDIR rc_case rc04_klems inputs/window_rc.pts -f klems_full.cal -b kbinS -bn Nkbins -m sky_glow -m ground_glow )
sed -n 1p "$CAL/inputs/sensors_rc.pts" > "$W/first.pts"
( cd "$W" && RAYPATH=.:$LIBDIR rc_case rc05_tregenza first.pts -f tregenza.cal -b tbin -bn Ntbins -m sky_glow )
# the custom bin of rc03 (16 bins: 8 azimuth sectors x 2 altitude bands): the
# coarse bins must agree one by one (relative RMS over the bins < 25 %)
( cd "$W" && rcontrib $OPTS -e 'mod(a,b)=a-floor(a/b)*b;az=mod(atan2(Dx,Dy)*180/PI,360);bin=floor(az/45)+8*if(Dz-.5,1,0)' \
    -b bin -bn 16 -m sky_glow $BOXS < inputs/sensors_rc.pts > "$W/rc03.txt" 2> "$W/rc03.err" )
r=$(awk '/^[0-9]/ { n++; if (NR == FNR) { for (i = 1; i <= NF; i++) a[n, i] = $i; next } }
         FNR == 1 && NR != 1 { n = 0 }
         NR != FNR && /^[0-9]/ { for (i = 1; i <= NF; i++) { d = a[n, i] - $i; dd += d * d; ss += $i * $i }; m++ }
         END { if (m != 3) print "records " m; else if (dd > 0.0625 * ss) printf "rel. RMS %.3f\n", sqrt(dd / ss) }' \
    "$W/rc03.txt" "$CAL/out/rc03_custom_bin.txt")
if [ -z "$r" ]; then pass rc03_custom_bin; else fail rc03_custom_bin "$r"; fi
# rc06: the three binnings of the first sensor trace the same rays, so
# their sums agree (exactly in Radiance; here within rounding)
s1=$(sed -n 1p "$W/rc01_mf2_before.txt" | awk '{for(i=1;i<=NF;i+=3) t+=$i} END {printf "%.9g", t}')
s2=$(sed -n 1p "$W/rc02_mf2_after.txt" | awk '{for(i=1;i<=NF;i+=3) t+=$i} END {printf "%.9g", t}')
if close "$s1" "$s2" 1e-6; then pass rc06_same_rays; else fail rc06_same_rays "$s1 vs $s2"; fi
# the same bins whatever the thread count (one .cal run per thread)
( cd "$W" && RAYPATH=.:$LIBDIR rcontrib -h -u- -n 2 -I+ -ab 1 -ad 256 -lw 1e-3 -f reinhartb.cal -e MF:2 -b rbin -bn Nrbins \
    -m sky_glow $BOXS < inputs/sensors_rc.pts > "$W/rc02_n2.txt" 2> /dev/null )
if cmp -s "$W/rc02_n2.txt" "$W/rc02_mf2_after.txt"; then pass rc_threads_same; else fail rc_threads_same "-n 2 differs from -n 1"; fi
