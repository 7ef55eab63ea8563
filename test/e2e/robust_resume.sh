# Fault injection: rcontrib (backward and photon-map mode), dctimestep -o
# series and mkpmap killed with SIGKILL at random points, or stopped by a full
# disk (a file-size limit; a small tmpfs when mounting is allowed), then run
# again: no truncated file under a final name, a clear error, and the resumed
# outputs byte for byte those of an uninterrupted run (docs/robustness.md).
. test/e2e/lib.sh
T=$(cd "$T" && pwd)
export SOURCE_DATE_EPOCH=1700000000   # the same header dates in every run
TOP=$PWD
{ roofbox_suns; printf 'void glow skyglow 0 0 4 1 1 1 0\nskyglow source sky 0 0 4 0 0 1 180\n'; } > "$T/box.rad"
awk 'BEGIN{srand(5); for(i=0;i<24000;i++) printf "%.4f %.4f 0.01 0 0 1\n", 0.1+0.8*rand(), 0.1+0.8*rand()}' > "$T/pts.txt"
RANDOM=$$   # the kill points differ from run to run; each is printed

# alive PID: running (not a zombie waiting to be reaped)
alive() { local a b st; { read -r a b st _ < "/proc/$1/stat"; } 2>/dev/null && [ "$st" != Z ]; }
# size FILE: bytes (0 if absent)
size() { stat -c %s "$1" 2>/dev/null || echo 0; }
# kill_when PID GLOB BYTES: SIGKILL the process once a file matching GLOB (in
# the current directory, hidden names included) holds BYTES, or after 20 s
kill_when() {
    local pid=$1 glob=$2 bytes=$3 k=0 f
    while alive "$pid" && [ $k -lt 1000 ]; do
        for f in $glob; do [ -e "$f" ] && [ "$(size "$f")" -ge "$bytes" ] && { kill -9 "$pid"; wait "$pid" 2>/dev/null; return 0; }; done
        sleep 0.02; k=$((k + 1))
    done
    kill -9 "$pid" 2>/dev/null; wait "$pid" 2>/dev/null; return 1
}
# same_files DIR_A DIR_B PATTERN...: every named file exists in both and is identical
same_files() {
    local a=$1 b=$2 f; shift 2
    for f in "$@"; do cmp -s "$a/$f" "$b/$f" || { echo "$f differs"; return 1; }; done
}
# only_complete DIR REF: every file of DIR is identical to REF's (REF may hold more)
only_complete() { diff -rq -x '.*.hdtmp.*' "$1" "$2" | grep -v "^Only in $2"; }
leftovers() { ls -a "$1" | grep hdtmp | tr '\n' ' '; }

# ---- rcontrib, backward mode: -ff and -fa records, two streams ----
RC="-faf -ab 1 -ad 64 -lw 1e-3 -I+ -o o_%s.mtx -m solar1 -m skyglow ../box.rad"
mkdir -p "$T/rc_ref" "$T/rc"
(cd "$T/rc_ref" && rcontrib $RC < ../pts.txt) || fail rc_reference
for i in 1 2 3; do
    rm -rf "$T/rc"; mkdir -p "$T/rc"; cd "$T/rc"
    at=$(( (RANDOM % 200 + 40) * 1024 ))   # kill once a temporary holds this much
    rcontrib $RC < ../pts.txt 2>/dev/null & pid=$!
    kill_when $pid '.o_*.hdtmp.*' $at; killed=$?
    bad=""; for f in o_solar1.mtx o_skyglow.mtx; do [ -e "$f" ] && ! cmp -s "$f" ../rc_ref/$f && bad="$bad $f"; done
    if [ -z "$bad" ]; then pass "rc_kill${i}_no_partial_final"; else fail "rc_kill${i}_no_partial_final" "$bad"; fi
    if rcontrib -r $RC < ../pts.txt 2>../rc_resume.err && same_files . ../rc_ref o_solar1.mtx o_skyglow.mtx >../rc_cmp.out
    then pass "rc_kill${i}_resume_identical ($([ $killed = 0 ] && echo "killed at $at bytes" || echo "finished before $at bytes"))"
    else fail "rc_kill${i}_resume_identical" "killed at $at bytes; $(cat ../rc_resume.err ../rc_cmp.out | tr '\n' ' ')"; fi
    l=$(leftovers .); if [ -z "$l" ]; then pass "rc_kill${i}_no_leftovers"; else fail "rc_kill${i}_no_leftovers" "$l"; fi
    cd "$TOP"
done
# -r on a complete output: nothing to do, files unchanged
cd "$T/rc"
if rcontrib -r $RC < ../pts.txt 2>../rc_again.err && grep -q "complete\|recovered" ../rc_again.err &&
   same_files . ../rc_ref o_solar1.mtx o_skyglow.mtx >/dev/null; then pass rc_resume_complete
else fail rc_resume_complete "$(cat ../rc_again.err)"; fi
# without -r or -fo an existing output is refused
check_fails rc_no_clobber "exists" rcontrib $RC
cd "$TOP"
# ascii records: killed and resumed
RCA="-ab 1 -ad 64 -lw 1e-3 -I+ -o a_%s.txt -m solar1 ../box.rad"
mkdir -p "$T/rca"; (cd "$T/rc_ref" && rcontrib $RCA < ../pts.txt)
cd "$T/rca"; rcontrib $RCA < ../pts.txt 2>/dev/null & pid=$!
kill_when $pid '.a_*.hdtmp.*' $(( (RANDOM % 300 + 70) * 1024 ))
if rcontrib -r $RCA < ../pts.txt 2>/dev/null && same_files . ../rc_ref a_solar1.txt >/dev/null; then pass rc_ascii_resume
else fail rc_ascii_resume "$(cmp a_solar1.txt ../rc_ref/a_solar1.txt 2>&1)"; fi
check_fails rc_resume_stdout "standard output" rcontrib -r -ab 1 -m solar1 ../box.rad
cd "$TOP"

# ---- full disk (file-size limit): a clear error, nothing under the final
# name, no temporary left; then a correct run ----
cd "$T/rc"; rm -f o_*
if (ulimit -f 100; rcontrib $RC < ../pts.txt) 2>../fsz.err; then fail rc_file_limit "succeeded under ulimit -f 100"
elif grep -q "o_s.*\.mtx: error writing output: File too large" ../fsz.err && [ ! -e o_solar1.mtx ] && [ ! -e o_skyglow.mtx ] &&
     [ -z "$(leftovers .)" ]; then pass rc_file_limit
else fail rc_file_limit "$(head -2 ../fsz.err | tr '\n' ' ') files: $(ls -a | tr '\n' ' ')"; fi
if rcontrib -r $RC < ../pts.txt 2>/dev/null && same_files . ../rc_ref o_solar1.mtx o_skyglow.mtx >/dev/null; then
    pass rc_file_limit_then_resume; else fail rc_file_limit_then_resume; fi
cd "$TOP"
# a small tmpfs (root only; skipped where mounting is not allowed)
mkdir -p "$T/mnt"
if mount -t tmpfs -o size=256k tmpfs "$T/mnt" 2>/dev/null; then
    cd "$T/mnt"; cp ../box.rad .
    RCM="-faf -ab 0 -I+ -o m_%s.mtx -m solar1 -m skyglow box.rad"
    if rcontrib $RCM < ../pts.txt 2>../enospc.err; then fail tmpfs_full "succeeded on a 256k file system"
    elif grep -q "No space left" ../enospc.err && [ ! -e m_solar1.mtx ] && [ -z "$(leftovers .)" ]; then pass tmpfs_full
    else fail tmpfs_full "$(head -2 ../enospc.err | tr '\n' ' ') $(ls -a | tr '\n' ' ')"; fi
    # with -y the need is known before the work: refused up front
    check_fails tmpfs_refused_up_front "needs about .* but only .* free" rcontrib -y 24000 $RCM
    cd "$TOP"; umount "$T/mnt"
else skip tmpfs_full "mounting a tmpfs is not allowed here"; fi

# ---- rcontrib, photon-map mode ----
check pm_build mkpmap -apC "$T/a.pm" 40k -apo port_m -apr 3 "$T/box.rad"
awk 'BEGIN{srand(9); for(i=0;i<40000;i++) printf "%.4f %.4f 0.01 0 0 1\n", 0.1+0.8*rand(), 0.1+0.8*rand()}' > "$T/pts2.txt"
RP="-faf -I+ -ab -1 -ap ../a.pm 60 -o p_%s.mtx -m solar1 -m solar2 ../box.rad"
mkdir -p "$T/rp"; (cd "$T/rc_ref" && rcontrib $RP < ../pts2.txt 2>/dev/null)
for i in 1 2; do
    rm -rf "$T/rp"; mkdir -p "$T/rp"; cd "$T/rp"
    at=$(( (RANDOM % 300 + 64) * 1024 ))
    rcontrib $RP < ../pts2.txt 2>/dev/null & pid=$!
    kill_when $pid '.p_*.hdtmp.*' $at; killed=$?
    if rcontrib -r $RP < ../pts2.txt 2>../rp.err && same_files . ../rc_ref p_solar1.mtx p_solar2.mtx >../rp_cmp.out
    then pass "rcap_kill${i}_resume_identical ($([ $killed = 0 ] && echo "killed at $at bytes" || echo "finished before $at bytes"))"
    else fail "rcap_kill${i}_resume_identical" "$(cat ../rp.err ../rp_cmp.out | tr '\n' ' ')"; fi
    cd "$TOP"
done

# ---- dctimestep -o series ----
awk 'BEGIN{print "#?RADIANCE"; print "NROWS=1500"; print "NCOLS=12"; print "NCOMP=3"; print "FORMAT=ascii"; print "";
     srand(3); for(r=0;r<1500;r++){for(c=0;c<12;c++) printf "%.5f %.5f %.5f ", rand(), rand(), rand(); print ""}}' > "$T/dc.mtx"
awk 'BEGIN{print "#?RADIANCE"; print "NROWS=12"; print "NCOLS=100"; print "NCOMP=3"; print "FORMAT=ascii"; print "";
     srand(4); for(r=0;r<12;r++){for(c=0;c<100;c++) {v=(c%7==0)?0:rand(); printf "%.4f %.4f %.4f ", v, v, v}; print ""}}' > "$T/sky.mtx"
DC="-N 1 -od -o s%03d.mtx ../dc.mtx ../sky.mtx"
DP="-x 50 -y 30 -o f%03d.hdr ../dc.mtx ../sky.mtx"
mkdir -p "$T/dc_ref" "$T/dcp_ref" "$T/dc"
(cd "$T/dc_ref" && dctimestep $DC) && (cd "$T/dcp_ref" && dctimestep $DP) || fail dc_reference
for i in 1 2; do
    rm -rf "$T/dc"; mkdir -p "$T/dc"; cd "$T/dc"
    n=$((RANDOM % 80 + 10))
    dctimestep $DC 2>/dev/null & pid=$!
    k=0; while alive $pid && [ "$(ls | wc -l)" -lt $n ] && [ $k -lt 2000 ]; do sleep 0.005; k=$((k + 1)); done
    kill -9 $pid 2>/dev/null; wait $pid 2>/dev/null
    got=$(ls | wc -l)
    bad=$(only_complete . ../dc_ref)
    if [ -z "$bad" ]; then pass "dc_kill${i}_finished_files_complete ($got of 100)"; else fail "dc_kill${i}_finished_files_complete" "$bad"; fi
    if dctimestep -r $DC 2>../dc.err && diff -rq . ../dc_ref >../dc_cmp.out && [ -z "$(leftovers .)" ]
    then pass "dc_kill${i}_resume_identical"
    else fail "dc_kill${i}_resume_identical" "$(cat ../dc.err ../dc_cmp.out | tr '\n' ' ') $(leftovers .)"; fi
    cd "$TOP"
done
# pictures: a file-size limit below one picture stops the series (a clear
# error, no partial picture); then the run resumes
rm -rf "$T/dc"; mkdir -p "$T/dc"; cd "$T/dc"
if (ulimit -f 2; dctimestep $DP) 2>../dcp.err; then fail dc_file_limit "succeeded under ulimit -f 2"
elif grep -q "f0.*\.hdr (File too large)" ../dcp.err && [ -z "$(leftovers .)" ]; then pass "dc_file_limit ($(ls f*.hdr 2>/dev/null | wc -l) pictures written)"
else fail dc_file_limit "$(head -2 ../dcp.err | tr '\n' ' ')"; fi
bad=$(only_complete . ../dcp_ref)
if [ -z "$bad" ]; then pass dc_file_limit_no_partial; else fail dc_file_limit_no_partial "$bad"; fi
if dctimestep -r $DP 2>../dcp2.err && diff -rq . ../dcp_ref >../dcp_cmp.out; then pass dc_pictures_resume_identical
else fail dc_pictures_resume_identical "$(cat ../dcp2.err ../dcp_cmp.out | tr '\n' ' ')"; fi
check_fails dc_resume_needs_o "needs -o" dctimestep -r ../dc.mtx ../sky.mtx
# results larger than the allocation limit: refused before the work, with the sizes
check_fails dc_absurd_refused "results of 1500 rows x 100 steps: refusing to allocate 3.4 MiB \(limit 1.0 MiB" \
    env HELIODON_MAX_ALLOC=1048576 dctimestep -od -o x%03d.mtx ../dc.mtx ../sky.mtx
cd "$TOP"
if mount -t tmpfs -o size=256k tmpfs "$T/mnt" 2>/dev/null; then
    check_fails dc_tmpfs_refused_up_front "-o .*f%03d.hdr \(100 files\) needs about .* but only .* free" dctimestep -x 50 -y 30 -o "$T/mnt/f%03d.hdr" "$T/dc.mtx" "$T/sky.mtx"
    umount "$T/mnt"
else skip dc_tmpfs_refused_up_front "mounting a tmpfs is not allowed here"; fi

# ---- mkpmap: killed while it spills sorted runs; the same command again
# removes the dead run's files and builds the same map ----
MK="-apC m.pm 150k -apo port_m -apr 5 -apB 200k ../box.rad"
mkdir -p "$T/mk_ref" "$T/mk"
(cd "$T/mk_ref" && mkpmap $MK) || fail mk_reference
cd "$T/mk"
mkpmap $MK 2>/dev/null & pid=$!
kill_when $pid '.m.pm.hdtmp.*' $(( (RANDOM % 64 + 16) * 1024 )); killed=$?
before=$(leftovers . | wc -w)
if [ ! -e m.pm ] || cmp -s m.pm ../mk_ref/m.pm; then pass mk_kill_no_partial_final; else fail mk_kill_no_partial_final; fi
[ $killed = 0 ] || rm -f m.pm   # finished before the kill: build it again all the same
if mkpmap $MK 2>../mk.err && cmp -s m.pm ../mk_ref/m.pm && [ -z "$(leftovers .)" ]; then
    pass "mk_kill_rerun_identical ($before stale files removed$([ $killed = 0 ] || echo ", finished before the kill"))"
else fail mk_kill_rerun_identical "$(head -2 ../mk.err | tr '\n' ' ') $(leftovers .)"; fi
rm -f m.pm
if (ulimit -f 200; mkpmap $MK) 2>../mkf.err; then fail mk_file_limit "succeeded under ulimit -f"
elif grep -q "File too large\|write failed" ../mkf.err && [ ! -e m.pm ] && [ -z "$(leftovers .)" ]; then pass mk_file_limit
else fail mk_file_limit "$(head -2 ../mkf.err | tr '\n' ' ') $(leftovers .)"; fi
check_fails mk_refused_up_front "needs about .* but only .* free" mkpmap -apC huge.pm 900g -apo port_m ../box.rad
cd "$TOP"
# the disk asked for up front: the map, plus sorted runs only when one source's photons exceed the
# memory budget (-apB); groups of sources that fit are sorted in memory and need no runs.  400k
# photons of 2 suns with -apB 15m (250k records): each sun fits, the map (~3.4 MB) fits a 6 MB tmpfs;
# the old estimate (runs for all photons whenever they exceed the budget: +8.2 MB) refused it.  With
# -apB 200k each sun is sorted in runs (+4.1 MB): refused up front, naming the runs.
mkdir -p "$T/mnt"
if mount -t tmpfs -o size=6m tmpfs "$T/mnt" 2>/dev/null; then
    if mkpmap -apC "$T/mnt/fit.pm" 400k -apo port_m -apr 5 -apB 15m "$T/box.rad" 2>"$T/mkfit.err" && [ -s "$T/mnt/fit.pm" ]
    then pass "mk_tmpfs_groups_in_memory ($(wc -c < "$T/mnt/fit.pm") bytes)"
    else fail mk_tmpfs_groups_in_memory "$(head -2 "$T/mkfit.err" | tr '\n' ' ')"; fi
    rm -f "$T/mnt/fit.pm"
    check_fails mk_tmpfs_runs_refused "one source's photons are sorted in runs on disk" \
        mkpmap -apC "$T/mnt/runs.pm" 400k -apo port_m -apr 5 -apB 200k "$T/box.rad"
    umount "$T/mnt"
else skip mk_tmpfs_groups_in_memory "mounting a tmpfs is not allowed here"; fi
