#!/bin/sh
# Run the test suites named as arguments (unit, fuzz, e2e) and print the totals
# as "N passed, N failed, N skipped".  Each unit test binary and each e2e
# script prints PASS:/FAIL:/SKIP: lines; a binary or script that exits
# non-zero without reporting a FAIL line counts as one failure.
# fuzz: each harness in $BUILD/fuzz runs over its regression inputs and
# seeds (test/fuzz/regress/NAME, test/fuzz/seeds/NAME; docs/fuzz.md).
# E2E_ONLY="a b": run only these e2e scripts (make check-asan).
set -u
BUILD=${BUILD:-build}
HELIODON_REF=${HELIODON_REF:-../shared/ref}
export HELIODON_REF
PATH="$(pwd)/$BUILD/bin:$PATH"
export PATH
HD_TEST_TMP="$(pwd)/$BUILD/tmp"
export HD_TEST_TMP
mkdir -p "$HD_TEST_TMP"
[ -d "$HELIODON_REF" ] || echo "NOTE: reference folder $HELIODON_REF not found: reference tests will SKIP"
log="$HD_TEST_TMP/test-log.txt"
: > "$log"
pass=0 fail=0 skip=0
run_one() {  # name command...
    name=$1; shift
    out="$HD_TEST_TMP/out.$$"
    start=$(date +%s)
    "$@" > "$out" 2>&1
    rc=$?
    end=$(date +%s)
    cat "$out" >> "$log"
    grep -E '^(FAIL|SKIP):' "$out"
    grep -E '^  ' "$out" | head -20
    p=$(grep -c '^PASS:' "$out"); f=$(grep -c '^FAIL:' "$out"); s=$(grep -c '^SKIP:' "$out")
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
        echo "FAIL: $name exited with status $rc"
        tail -5 "$out" | sed 's/^/  /'
        f=1
    fi
    pass=$((pass + p)); fail=$((fail + f)); skip=$((skip + s))
    echo "  [$name: $p passed, $f failed, $s skipped, $((end - start)) s]"
    rm -f "$out"
}
for suite in "$@"; do
    case $suite in
    unit)
        for t in "$BUILD"/test/test_*; do
            [ -x "$t" ] || continue
            run_one "$(basename "$t")" "$t"
        done ;;
    fuzz)
        for t in "$BUILD"/fuzz/fuzz_*; do
            [ -x "$t" ] || continue
            h=$(basename "$t"); h=${h#fuzz_}
            set --
            for d in test/fuzz/regress/"$h" test/fuzz/seeds/"$h"; do [ -d "$d" ] && set -- "$@" "$d"; done
            [ $# -gt 0 ] && run_one "$(basename "$t")" "$t" -q "$@"
        done ;;
    e2e)
        for t in test/e2e/*.sh; do
            [ -f "$t" ] || continue
            case $(basename "$t") in lib.sh) continue ;; esac
            if [ -n "${E2E_ONLY:-}" ]; then
                case " $E2E_ONLY " in *" $(basename "$t" .sh) "* | *" $(basename "$t") "*) ;; *) continue ;; esac
            fi
            run_one "$(basename "$t")" bash "$t"
        done ;;
    slurm)
        for t in test/slurm/test_*.sh; do
            [ -f "$t" ] || continue
            run_one "$(basename "$t")" bash "$t"
        done ;;
    esac
done
echo "full log: $log"
echo "$pass passed, $fail failed, $skip skipped"
[ "$fail" -eq 0 ]
