# rcontrib -r with -c 0 (docs/robustness.md): as Radiance 6.1 does, the one
# record of sums an earlier run wrote is read back and the new run's rays
# are added to it, in backward and photon-map mode.  A missing file adds
# nothing (with a warning); a file of another format or a cut record is an
# error that leaves the file as it was.
. test/e2e/lib.sh
T=$(cd "$T" && pwd)
{ roofbox_suns; printf 'void glow skyglow 0 0 4 1 1 1 0\nskyglow source sky 0 0 4 0 0 1 180\n'; } > "$T/box.rad"
awk 'BEGIN{srand(3); for(i=0;i<200;i++) printf "%.4f %.4f 0.01 0 0 1\n", 0.1+0.8*rand(), 0.1+0.8*rand()}' > "$T/p1.txt"
awk 'BEGIN{srand(4); for(i=0;i<150;i++) printf "%.4f %.4f 0.01 0 0 1\n", 0.1+0.8*rand(), 0.1+0.8*rand()}' > "$T/p2.txt"

# values A FILE: the numbers of a record file (header skipped), one a line
values() {
    case $1 in
    a) getinfo - < "$2" | tr -s ' \t' '\n\n' | grep . ;;
    d) getinfo - < "$2" | od -An -v -tf8 | tr -s ' ' '\n' | grep . ;;
    esac
}
# sum_ok FMT RTOL B A C: every value of B within RTOL of A + C, and not all zero
sum_ok() {
    values "$1" "$4" > "$T/va"; values "$1" "$5" > "$T/vc"; values "$1" "$3" > "$T/vb"
    paste "$T/vb" "$T/va" "$T/vc" | awk -v t="$2" '
        { n++; s = $2 + $3; d = $1 - s; if (d < 0) d = -d; m = s < 0 ? -s : s
          if (d > t * m + 1e-300) { printf "value %d: %s, expected %s + %s\n", n, $1, $2, $3; bad = 1; exit }
          if (m > 0) nz++ }
        END { if (bad) exit 1; if (n < 3 || !nz) { print "no values or all zero: " n; exit 1 } }'
}

for mode in back pmap; do
    if [ $mode = back ]; then
        OPT="-I+ -ab 1 -ad 64 -lw 1e-3 -m solar1 -m skyglow $T/box.rad"; outs="x_solar1.mtx x_skyglow.mtx"
    else
        check pm_build mkpmap -apC "$T/a.pm" 8k -apo port_m -apr 3 -n 1 "$T/box.rad"
        OPT="-I+ -ab -1 -ap $T/a.pm 40 -m solar1 -m solar2 $T/box.rad"; outs="x_solar1.mtx x_solar2.mtx"
    fi
    for f in a d; do
        mkdir -p "$T/$mode$f/A" "$T/$mode$f/B" "$T/$mode$f/C"
        (cd "$T/$mode$f/A" && rcontrib -c 0 -fa$f -o x_%s.mtx $OPT < ../../p1.txt) 2>"$T/err" &&
        (cd "$T/$mode$f/C" && rcontrib -c 0 -fa$f -o x_%s.mtx $OPT < ../../p2.txt) 2>"$T/err" ||
            fail "${mode}_${f}_runs" "$(cat "$T/err")"
        cd "$T/$mode$f/B" && cp ../A/x_* . &&
            rcontrib -r -c 0 -fa$f -o x_%s.mtx $OPT < ../../p2.txt 2>"$T/err" || fail "${mode}_$f" "$(cat "$T/err")"
        # ascii records hold 7 digits; doubles are summed in another order
        tol=2e-6; [ $f = d ] && tol=1e-12
        for o in $outs; do
            if msg=$(sum_ok $f $tol "$T/$mode$f/B/$o" "$T/$mode$f/A/$o" "$T/$mode$f/C/$o"); then
                pass "${mode}_${f}_${o%.mtx}_sum_of_both_runs"
            else fail "${mode}_${f}_${o%.mtx}_sum_of_both_runs" "$msg"; fi
        done
    done
done
cd "$T/backd/B"
if [ ! -s x_solar1.mtx ] || grep -aq -- " -r " x_solar1.mtx; then fail header_without_r; else pass header_without_r; fi

# no earlier file: a warning, and the sums of this run alone
mkdir -p "$T/miss" && cd "$T/miss"
OPT="-I+ -ab 1 -ad 64 -lw 1e-3 -m solar1 -m skyglow $T/box.rad"
if rcontrib -r -c 0 -fad -o x_%s.mtx $OPT < ../p2.txt 2>err && grep -q "x_solar1.mtx: missing reload file" err &&
   [ "$(values d x_solar1.mtx)" = "$(values d ../backd/C/x_solar1.mtx)" ]; then pass missing_file_starts_at_zero
else fail missing_file_starts_at_zero "$(cat err)"; fi

# another format, a cut record: an error, the file left as it was
cp ../backa/A/x_solar1.mtx ../backa/A/x_skyglow.mtx .
check_fails format_mismatch "x_solar1.mtx: format mismatch: the file holds FORMAT=ascii, this run writes double" \
    rcontrib -r -c 0 -fad -o x_%s.mtx $OPT < ../p2.txt
# the last value, its tab and the newline cut off
head -c -14 ../backa/A/x_solar1.mtx > x_solar1.mtx; cp x_solar1.mtx cut.keep
check_fails cut_record "x_solar1.mtx: byte offset [0-9]+: the record of sums ends after 2 of 3 values" \
    rcontrib -r -c 0 -o x_%s.mtx $OPT < ../p2.txt
if cmp -s x_solar1.mtx cut.keep; then pass cut_record_file_unchanged; else fail cut_record_file_unchanged; fi
check_fails stdout_refused "cannot recover from the standard output" rcontrib -r -c 0 $OPT < ../p2.txt
check_fails picture_refused "-c 0 and picture output" rcontrib -r -c 0 -ffc -x 1 -y 1 -o y_%s.hdr $OPT < ../p2.txt
