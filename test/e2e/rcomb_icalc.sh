# rcomb, icalc and tabfunc beyond the Radiance reference cases of
# cal_tools.sh: values against analytic results, thread independence,
# formats, and the error cases (bad expressions named by file, line and
# column; bad matrices named by file; dimension and option mismatches).
. test/e2e/lib.sh

# a 40 x 5 x 3 matrix: element (r,c) = (r+c, r-c, r*c)
awk 'BEGIN { print "#?RADIANCE"; print "NROWS=40"; print "NCOLS=5"; print "NCOMP=3"; print "FORMAT=ascii"; print ""
             for (r = 0; r < 40; r++) { for (c = 0; c < 5; c++) printf "%d %d %d\t", r + c, r - c, r * c; print "" } }' > "$T/m.mtx"

# co(p) with r, c, ci(i,p), nfiles, ncomp: every value against awk
rcomb -fa -e 'co(p)=select(p,ci(1,1)-r-c,ci(1,2)-(r-c),ci(1,3)+10*nfiles+ncomp)' "$T/m.mtx" > "$T/co.txt" 2> "$T/co.err"
bad=$(data_values "$T/co.txt" | awk '{ e = int((NR - 1) / 3); k = (NR - 1) % 3; r = int(e / 5); c = e % 5
        want = k < 2 ? 0 : r * c + 13; if ($1 != want) n++ } END { print NR, n + 0 }')
[ "$bad" = "600 0" ] && [ ! -s "$T/co.err" ] && pass co_function_r_c || fail co_function_r_c "$bad $(cat "$T/co.err")"

# a variable co: the same operation on every component; the trailing -s
rcomb -fa -e 'co=ci(1)*ci(2)' "$T/m.mtx" "$T/m.mtx" -s 0.5 > "$T/sq.txt"
bad=$(paste <(data_values "$T/sq.txt") <(data_values "$T/m.mtx") | awk '{ if ($1 != $2 * $2 / 2) n++ } END { print NR, n + 0 }')
[ "$bad" = "600 0" ] && pass co_variable_trailing_s || fail co_variable_trailing_s "$bad"

# threads: -n 3 gives the same bytes (header dates aside)
rcomb -fa -e 'co(p)=ci(1,p)*sin(r+c*p)' "$T/m.mtx" | sed '/^CAPDATE=/d; /^GMT=/d' > "$T/n1"
rcomb -n 3 -fa -e 'co(p)=ci(1,p)*sin(r+c*p)' "$T/m.mtx" | sed '/^CAPDATE=/d; /^GMT=/d;s/-n 3 //' > "$T/n3"
cmp -s "$T/n1" "$T/n3" && pass threads_same || fail threads_same "-n 3 differs from -n 1"

# float and double outputs read back equal the ascii ones
rcomb -fd -c .25 .5 .25 "$T/m.mtx" > "$T/d.mtx"
rcomb -fa "$T/d.mtx" > "$T/d.txt"; rcomb -fa -c .25 .5 .25 "$T/m.mtx" > "$T/a.txt"
[ "$(data_values "$T/d.txt")" = "$(data_values "$T/a.txt")" ] && pass double_round_trip || fail double_round_trip "values differ"
grep -q '^NCOMP=1$' "$T/a.txt" && pass ncomp_after_c || fail ncomp_after_c "$(grep NCOMP "$T/a.txt")"

# -fc: an RGB picture with the matrix dimensions in the resolution string
rcomb -fc -s .01 "$T/m.mtx" > "$T/p.hdr"
if grep -aq '^FORMAT=32-bit_rle_rgbe$' "$T/p.hdr" && grep -aEq '^-Y +40 \+X +5$' "$T/p.hdr"; then pass picture_output
else fail picture_output "$(getinfo < "$T/p.hdr" | tr '\n' '|')"; fi

# the header: each input named, the command line
rcomb -fa "$T/m.mtx" -s 2 "$T/m.mtx" > "$T/h.txt"
[ "$(grep -c "^$T/m.mtx:\$" "$T/h.txt")" = 2 ] && grep -q '^rcomb -fa ' "$T/h.txt" && pass header_inputs || fail header_inputs "$(head -5 "$T/h.txt" | tr '\n' '|')"

# domain error of ci(): a warning, value 0, silenced by -w
rcomb -fa -e 'co=ci(3)' "$T/m.mtx" > "$T/dom.txt" 2> "$T/dom.err"
if [ $? = 0 ] && grep -q 'ci(): domain error' "$T/dom.err" && [ "$(data_values "$T/dom.txt" | sort -u)" = "0.0000000e+00" ]; then pass ci_domain_warning
else fail ci_domain_warning "$(head -2 "$T/dom.err")"; fi
rcomb -w -fa -e 'co=ci(3)' "$T/m.mtx" > /dev/null 2> "$T/dom2.err"
[ ! -s "$T/dom2.err" ] && pass ci_domain_w || fail ci_domain_w "$(cat "$T/dom2.err")"

# ---- errors ----
printf 'a = 1;\nco = ci(1) * (a + ;\n' > "$T/bad.cal"
check_fails bad_cal_file_line_column "bad.cal, line 2, column 19" rcomb -f "$T/bad.cal" "$T/m.mtx"
check_fails bad_expr_caret "\\^ unexpected character" rcomb -e 'co=ci(1)*' "$T/m.mtx"
check_fails undefined_variable "nosuch: undefined variable" rcomb -e 'co=nosuch' "$T/m.mtx"
head -c 150 "$T/m.mtx" > "$T/trunc.mtx"
check_fails truncated_matrix "trunc.mtx" rcomb "$T/trunc.mtx"
printf '#?RADIANCE\nNROWS=2\nNCOLS=2\nNCOMP=3\nFORMAT=ascii\n\n1 2 3 4 5 x\n' > "$T/word.mtx"
check_fails bad_number "word.mtx" rcomb "$T/word.mtx"
printf '#?RADIANCE\nNROWS=2\nNCOLS=2\nNCOMP=3\nFORMAT=float\n\nabc' > "$T/short.mtx"
check_fails short_binary "short.mtx" rcomb "$T/short.mtx"
check_fails missing_file "nofile.mtx" rcomb "$T/nofile.mtx"
rcomb -fa -c 1 0 0 "$T/m.mtx" > "$T/m1.mtx"
check_fails size_mismatch "mismatch in size or #components" rcomb "$T/m.mtx" "$T/m1.mtx"
check_fails c_coefficients "-c must have N x 3 coefficients" rcomb -c 1 2 "$T/m.mtx"
check_fails s_factors "-s must have one or 3 factors" rcomb -s 1 2 "$T/m.mtx"
check_fails symbolic_one_comp "requires at least 3 components" rcomb -c Y "$T/m1.mtx"
check_fails mcat_rows "does not match number of rows" rcomb "$T/m.mtx" -m "$T/m.mtx"
check_fails no_input "need at least one input" rcomb -fa
rcomb -fa "$T/m.mtx" < /dev/null > /dev/null 2>&1 && pass ok_baseline || fail ok_baseline "plain rcomb failed"

# ---- icalc ----
out=$(printf 'sq(x) = x*x\nsq(4)\n$1 + $\nk : 2\n$2 * k\n$7\n' | icalc 2> "$T/ic.err")
[ "$out" = "$(printf '$1=16\n$2=32\n$3=64\n$4=0')" ] && grep -q '^\$7: illegal result$' "$T/ic.err" && pass icalc_results \
    || fail icalc_results "$(echo "$out" | tr '\n' ' ') $(cat "$T/ic.err")"
# the printed definitions compute what the originals compute
printf 'g(x,y) = -(x-y)^2/(y/(x*2)) - x - (y-1) + 2^3^2 + (2^3)^2 - 8/2/2\n> %s\n' "$T/def.cal" | icalc > /dev/null
a=$(rcalc -n -e 'g(x,y) = -(x-y)^2/(y/(x*2)) - x - (y-1) + 2^3^2 + (2^3)^2 - 8/2/2;$1=g(3,5);$2=g(-1.5,2)')
b=$(rcalc -n -f "$T/def.cal" -e '$1=g(3,5);$2=g(-1.5,2)')
[ -n "$a" ] && [ "$a" = "$b" ] && pass icalc_print_round_trip || fail icalc_print_round_trip "$a vs $b: $(cat "$T/def.cal")"
printf 'a = 1\nb = (a +\nb = 2\nb\n' | icalc > "$T/ic2.out" 2> "$T/ic2.err"
grep -q "')' expected\|unexpected" "$T/ic2.err" && [ "$(cat "$T/ic2.out")" = '$1=2' ] && pass icalc_error_recovers \
    || fail icalc_error_recovers "$(cat "$T/ic2.out" "$T/ic2.err" | tr '\n' ' ')"
check_fails icalc_bad_file "bad.cal, line 2, column 19" icalc "$T/bad.cal"

# ---- tabfunc ----
printf '# comment\n0 0 10\n1 2 10\n3 6 40\n4 8 50\n' > "$T/tab.dat"
tabfunc -i f g < "$T/tab.dat" > "$T/tab.cal"
got=$(rcalc -n -f "$T/tab.cal" -e '$1=f(-1);$2=f(.5);$3=f(2);$4=f(3.5);$5=f(9);$6=g(2);$7=g(3.25)')
[ "$got" = "$(printf '0\t1\t4\t7\t8\t25\t42.5')" ] && pass tabfunc_interpolate || fail tabfunc_interpolate "$got"
printf '0 1\n2 2\n1 3\n5 4\n' > "$T/nf.dat"
check_fails tabfunc_not_function "input not a function" tabfunc f < "$T/nf.dat"
printf '0 1 2\n1 2\n' > "$T/few.dat"
check_fails tabfunc_few_columns "input line 2: too few columns" tabfunc f g < "$T/few.dat"
printf '0 1 2\n1 2 3z\n' > "$T/bad.dat"
check_fails tabfunc_bad_number "input line 2: bad floating-point format" tabfunc f g < "$T/bad.dat"
