#!/bin/sh
# Malformed scenes: oconv exits non-zero with a message naming file:line
# and what was expected; nothing is written; no crash.
. test/e2e/lib.sh
bad() {  # name pattern text
    printf '%b' "$3" > "$T/$1.rad"
    check_fails "$1" "$2" oconv "$T/$1.rad"
    if oconv "$T/$1.rad" > "$T/$1.oct" 2>/dev/null; then :; else
        [ -s "$T/$1.oct" ] && fail "$1_no_output" "partial cache written" || true
    fi
}
bad wrong_count      "wrong_count.rad:2: plastic m: expected 0 strings and 5 reals \\(R G B spec rough\\), got 0 strings and 4 reals" \
    '# comment\nvoid plastic m 0 0 4 .5 .5 .5 0\n'
bad unknown_modifier "unknown_modifier.rad:3: polygon p: undefined modifier 'nomat'" \
    'void plastic m 0 0 5 .5 .5 .5 0 0\n\nnomat polygon p 0 0 9 0 0 0 1 0 0 0 1 0\n'
bad used_before_def  "used_before_def.rad:1: sphere s: undefined modifier 'm'" \
    'm sphere s 0 0 4 0 0 0 1\nvoid plastic m 0 0 5 .5 .5 .5 0 0\n'
bad non_numeric      "non_numeric.rad:4: sphere s: expected real argument 3 of 4, got '1,5'" \
    'void plastic m 0 0 5 .5 .5 .5 0 0\nm sphere s\n0 0 4\n0 0 1,5 1\n'
bad truncated        "truncated.rad:1: polygon p: expected real argument 10 of 12, got end of data" \
    'void polygon p 0 0 12 0 0 0 1 0 0 1 1 0\n'
bad unterminated_cmd "unterminated_cmd.rad:2: .*line 1: plastic m: expected real argument 3 of 5, got end of data" \
    '# output ends inside a primitive\n!echo void plastic m 0 0 5 1 1\n'
bad failed_cmd       "failed_cmd.rad:1: command '!sh -c .exit 7.' failed with exit status 7" \
    "!sh -c 'exit 7'\n"
bad missing_include  "missing_include.rad:1: command '!xform .*/nothere.rad' failed with exit status 1" \
    "!xform -t 0 0 1 $T/nothere.rad\n"
bad unknown_type     "unknown_type.rad:1: unknown primitive type 'polygone'" \
    'void polygone p 0 0 9 0 0 0 1 0 0 0 1 0\n'
bad bad_ring         "bad_ring.rad:1: ring r: negative radius" \
    'void ring r 0 0 8 0 0 0 0 0 1 -1 2\n'
check_fails missing_file "cannot open scene file '.*/absent.rad'" oconv "$T/absent.rad"
check_fails no_files "no scene files" oconv
check_fails bad_cache "corrupt or truncated|unexpected end of data" sh -c "oconv '$T/wrong_count.rad' >/dev/null 2>&1; printf '#?RADIANCE\nFORMAT=heliodon_scene\n\nHDSCENE\n' > '$T/trunc.oct'; oconv -p '$T/trunc.oct'"
# frozen Radiance octree (no scene file list): refused with a clear message
printf '#?RADIANCE\nFORMAT=Radiance_octree\n\n\001\037-1\000-1\000-1\0002\000\000' > "$T/frozen.oct"
check_fails frozen_octree "frozen Radiance octree" oconv -p "$T/frozen.oct"
# warnings (not errors), as Radiance gives them: zero-area and non-planar polygons
printf 'void polygon p 0 0 12 0 0 0 1 0 0 1 1 .5 0 1 0\nvoid polygon q 0 0 9 0 0 0 1 0 0 2 0 0\n' > "$T/warn.rad"
if oconv "$T/warn.rad" > "$T/warn.oct" 2> "$T/warn.err" && grep -q 'warn.rad:1: polygon p is not planar' "$T/warn.err" \
    && grep -q 'warn.rad:2: polygon q has zero area' "$T/warn.err"; then pass polygon_warnings
else fail polygon_warnings "$(cat "$T/warn.err")"; fi
# a file that includes itself stops at the nesting limit (in-process and through xform)
printf '!cat %s/self.rad\n' "$T" > "$T/self.rad"
check_fails self_include "nested more than 32 deep" oconv "$T/self.rad"
printf 'void plastic m 0 0 5 1 1 1 0 0\n!xform -t 1 0 0 selfx.rad\n' > "$T/selfx.rad"
check_fails self_include_xform "nested more than 32 deep" sh -c "cd '$T' && oconv selfx.rad"
