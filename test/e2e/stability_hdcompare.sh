#!/bin/sh
# hdcompare: values against an independent awk computation on the reference
# rtrace outputs, and every bad-input class (clear error, non-zero exit).
. test/e2e/lib.sh
B=$REF/scenes/box
if have_ref scenes/box; then
    hdcompare -m "$B/a1_clear_ab6.dat" "$B/a1_clear_conv.dat" > "$T/c" 2>"$T/err" || fail matrix_rms "$(cat "$T/err")"
    got=$(awk '$1=="rms_rel"{print $2}' "$T/c")
    want=$(paste <(data_values "$B/a1_clear_ab6.dat" | paste - - -) <(data_values "$B/a1_clear_conv.dat" | paste - - -) 2>/dev/null |
           awk '{a=.265074126*$1+.670114631*$2+.064811243*$3; b=.265074126*$4+.670114631*$5+.064811243*$6; d=(a-b)/b; s+=d*d; n++}
                END{printf "%.6g", sqrt(s/n)}')
    if [ -n "$got" ] && close "$got" "$want" 1e-4; then pass "matrix_rms ($got)"; else fail matrix_rms "hdcompare $got, awk $want"; fi
    # a picture against itself: 0, and E_v/DGP as the header view gives them
    hdcompare "$B/a2_clear_fish.hdr" "$B/a2_clear_fish.hdr" > "$T/p" 2>"$T/err"
    if grep -q '^rms_rel 0$' "$T/p" && grep -q '^dgp_diff 0$' "$T/p"; then pass picture_self_zero
    else fail picture_self_zero "$(head -3 "$T/p" "$T/err" | tr '\n' ' ')"; fi
    # -s scales the test: a half-bright copy is 50 % low everywhere, doubled back it is 0
    hdcompare -s 0.5 -m "$B/a1_clear_conv.dat" "$B/a1_clear_conv.dat" > "$T/s" 2>"$T/err"
    hdcompare -s 2 "$B/a2_clear_fish.hdr" "$B/a2_clear_fish.hdr" > "$T/s2" 2>>"$T/err"
    if grep -q '^total_rel -0.5$' "$T/s" && awk '$1=="total_rel"{x=$2} END{exit !(x > 0.99 && x < 1.01)}' "$T/s2"; then pass scale_factor
    else fail scale_factor "$(grep total_rel "$T/s" "$T/s2" "$T/err" | tr '\n' ' ')"; fi
    check_fails size_mismatch "sizes differ" hdcompare "$B/a2_clear_fish.hdr" "$B/a3_img/skysun_0.hdr"
    check_fails matrix_size_mismatch "sizes differ" hdcompare -m "$B/a1_clear_conv.dat" "$B/a3_res_sensors_skysun.mtx"
else skip hdcompare_ref "no reference folder $REF"; fi
check_fails missing_file "nonexistent" hdcompare "$T/nonexistent.hdr" "$T/nonexistent.hdr"
printf 'garbage\n' > "$T/g.hdr"
check_fails garbage_picture "g.hdr" hdcompare "$T/g.hdr" "$T/g.hdr"
check_fails bad_floor "-f expects a number" hdcompare -f abc "$T/g.hdr" "$T/g.hdr"
check_fails bad_factor "factor" hdcompare -r 0 "$T/g.hdr" "$T/g.hdr"
check_fails usage "usage" hdcompare onlyone
check_fails bad_scale "-s expects" hdcompare -s -1 "$T/g.hdr" "$T/g.hdr"
{ printf '#?RADIANCE\nNROWS=2\nNCOLS=1\nNCOMP=3\nBigEndian=0\nFORMAT=float\n\n'
  printf '\000\000\200\077\000\000\200\077\000\000\200\077\000\000\300\177\000\000\300\177\000\000\300\177'; } > "$T/nan.dat"
printf '#?RADIANCE\nNCOMP=3\nFORMAT=ascii\n\n1 1 1\n2 2 2\n' > "$T/ok.dat"
hdcompare -m "$T/nan.dat" "$T/ok.dat" > "$T/n" 2>&1; rc=$?
if [ $rc = 3 ] && grep -q '^nonfinite_test 1$' "$T/n"; then pass nan_counted_exit3
else fail nan_counted_exit3 "exit $rc: $(head -3 "$T/n" | tr '\n' ' ')"; fi
