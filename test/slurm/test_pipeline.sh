#!/usr/bin/env bash
# The annual pipeline submitted to a real one-machine SLURM cluster (make SUBMIT=slurm; munged,
# slurmctld and slurmd started here in a temporary folder, 4 CPUs configured on 2 cores so that
# array tasks overlap, stopped at the end): the tiny office case (4 weather records, 32x32, MF:1,
# clear glass; the photon map in 3 emission shards) against the same case run on this machine
# without SLURM, in the same folder (headers name the files they were made from) and with
# SOURCE_DATE_EPOCH set (header dates).  Every output file must be byte-identical, except what
# records how the run went: timings.txt and the report pages that print it, the *_seconds lines of
# summary.txt/notes.txt (compared without them), and the photon map's text header (it names
# mkpmap -apJ and the shards; its binary part is compared).  Then one array task
# of the DC_sun stage is cancelled (scancel) while it waits for the photon map: status shows it failed and the later
# stages never start; `make slurm-resubmit` resubmits that task only and the run completes with
# the same outputs.  Also: SUBMIT=slurm refuses bad input before submitting anything.
. "$(dirname "$0")/../e2e/lib.sh"
ROOT=$(pwd)
T=$(cd "$T" && pwd)
. "$(dirname "$0")/lib.sh"
# tasks run make in scenes/office with heliodon's programs: the jobs inherit this PATH (sbatch
# exports the submitting environment)
export PATH
export SOURCE_DATE_EPOCH=1700000000
# the make that runs this test (make -j2 check-slurm) must not hand its jobserver to the jobs
unset MAKEFLAGS MFLAGS MAKELEVEL

O=$ROOT/scenes/office
izmir_wea "$T/w.wea" '3 21 1.5 0 0' '3 21 10.5 820 110' '3 21 14.5 780 130' '12 21 12.5 60 180'
ARGS=(WEATHER="$T/w.wea" CONFIG=glass VIEW=v1 RES=32 MF=1 PHOTONS=100k BANDWIDTH=50 NPROC=1 IMAGES=1
      SKY_OPTS="-ab 2 -ad 128 -lw 1e-3" FEN_OPTS="-ab 2 -ad 128 -lw 1e-3" FENSUN_OPTS="-ab 1 -ad 32 -lw 1e-3"
      FENSUN_C=2 GROUNDPTS=256 SUN_UNIT=1)
RUN=$T/run      # every run is made here and moved aside afterwards
LOCAL=$T/local
if make -s -C "$O" "${ARGS[@]}" OUT="$RUN" > "$T/local.log" 2>&1 && mv "$RUN" "$LOCAL"; then pass local_run
else fail local_run "$(tail -3 "$T/local.log" | tr '\n' ' ')"; exit 0; fi

# compare RUN with the local run: every file, byte for byte, with the stated exceptions
compare_runs() {  # NAME RUN
    local n=$1 run=$2 bad="" f
    ( cd "$LOCAL" && find . -type f | sort ) > "$T/files.local"
    # the SLURM runs' pieces (photon shards, DC record pieces, hour pieces) are left out: the joined files are compared
    ( cd "$run" && find . -type f ! -path './.hdslurm/*' ! -path './pm/*' ! -path '*.p/*' ! -path '*/compose.h/*' ! -name slurm.plan | sort ) > "$T/files.$n"
    if ! cmp -s "$T/files.local" "$T/files.$n"; then
        fail "${n}_same_files" "$(diff "$T/files.local" "$T/files.$n" | head -5 | tr '\n' ' ')"; return
    fi
    pass "${n}_same_files"
    while read -r f; do
        case $f in
        ./timings.txt|./report/index.html|./report/*/index.html) continue ;;
        */summary.txt|*/notes.txt)
            cmp -s <(grep -v '_seconds:' "$LOCAL/$f") <(grep -v '_seconds:' "$run/$f") || bad="$bad $f" ;;
        ./sun.cpm)  # the binary part: everything after the header's blank line
            cmp -s <(sed '1,/^$/d' "$LOCAL/$f") <(sed '1,/^$/d' "$run/$f") || bad="$bad $f" ;;
        *) cmp -s "$LOCAL/$f" "$run/$f" || bad="$bad $f" ;;
        esac
    done < "$T/files.local"
    if [ -z "$bad" ]; then pass "${n}_byte_identical"; else fail "${n}_byte_identical" "differ:$(echo $bad | cut -c1-300)"; fi
}

# DC_sun in units of one sun (3 units) gives the pictures of one rcontrib run over all suns (pixels; the
# header names the unit's modifier file)
if make -s -C "$O" "${ARGS[@]}" SUN_UNIT=0 OUT="$T/nounits" "$T/nounits/v1/dcsun" > "$T/nounits.log" 2>&1; then
    bad=""; n=0
    for f in "$T/nounits/v1/dcsun/"*.hdr; do
        n=$((n + 1)); cmp -s <(sed '1,/^$/d' "$f") <(sed '1,/^$/d' "$LOCAL/v1/dcsun/$(basename "$f")") || bad="$bad $(basename "$f")"
    done
    if [ "$n" -ge 3 ] && [ -z "$bad" ] && [ "$(ls "$LOCAL/v1/dcsun" | wc -l)" = "$n" ]; then pass sun_units_same_pixels
    else fail sun_units_same_pixels "$n pictures; differ:$bad"; fi
else fail sun_units_same_pixels "$(tail -3 "$T/nounits.log" | tr '\n' ' ')"; fi

# ---- the whole run through SLURM ----
# DCs in 3 record pieces (image rows; dcsun stays in units of one sun), the composition in 2 pieces
# of the daylight hours: the joined outputs must be the one-machine run's
PIECES="DC_PIECES=3 HOUR_PIECES=2"
S1=$RUN
if make -s -C "$O" "${ARGS[@]}" OUT="$S1" SUBMIT=slurm SLURM_PM_SHARDS=3 SLURM_MEM=500M $PIECES > "$T/submit1.log" 2>&1; then
    pass submit
else fail submit "$(tail -3 "$T/submit1.log" | tr '\n' ' ')"; exit 0; fi
n=$(awk '!/^#/ && NF' "$S1/slurm.plan" | wc -l)
if [ "$n" = 8 ] && grep -q '^photons 3 prep ' "$S1/slurm.plan" && grep -q '^dc 9 prep ' "$S1/slurm.plan" &&
   grep -q '^dcjoin 4 dc,dcsun ' "$S1/slurm.plan" && grep -q '^compose 2 prep,dc,dcsun,dcjoin ' "$S1/slurm.plan" &&
   grep -q "^dcsun $(wc -l < "$LOCAL/sunits.done") pmmerge " "$S1/slurm.plan"; then pass plan_stages
else fail plan_stages "$(cut -c1-40 "$S1/slurm.plan" | tr '\n' '|')"; fi
if scripts/hdslurm wait "$S1" 900 > "$T/wait1.log" 2>&1; then pass all_tasks_done
else fail all_tasks_done "$(cat "$T/wait1.log" | tr '\n' '|')"; tail -20 "$S1"/.hdslurm/log/*.out > "$T/tasklogs.txt" 2>&1; fi
compare_runs slurm "$S1"
# the three shards each hold a part of the sources, the merged map all of them
if [ -s "$S1/pm/shard0.cpm" ] && [ -s "$S1/pm/shard2.cpm" ] && ! cmp -s "$S1/pm/shard0.cpm" "$S1/pm/shard1.cpm"; then pass shards_differ
else fail shards_differ "$(ls -l "$S1/pm" | tr '\n' ' ')"; fi
mv "$RUN" "$T/slurm1"

# ---- one task killed, only that one resubmitted ----
S2=$RUN
make -s -C "$O" "${ARGS[@]}" OUT="$S2" SUBMIT=slurm SLURM_PM_SHARDS=3 SLURM_MEM=500M $PIECES > "$T/submit2.log" 2>&1
jsun=$(awk '$1 == "dcsun" {print $2}' "$S2/.hdslurm/jobs.tsv")
# DC_sun's first unit is cancelled while its job waits for the photon map (prep, shards and merge
# run first: deterministic, whatever the machine's speed); the other units run, the composition
# and the report can never start (afterok)
scancel "${jsun}_0"
for i in $(seq 1500); do [ -z "$(squeue -h -j "$jsun" -o '%i' 2>/dev/null)" ] && break; sleep 0.2; done
sleep 1
make -s -C "$O" "${ARGS[@]}" $PIECES OUT="$S2" slurm-status > "$T/status2.log" 2>&1; rc=$?
if [ $rc -ne 0 ] && awk '$1 == "dcsun" && $5 == "0" {ok = 1} END {exit !ok}' "$T/status2.log" && [ ! -e "$S2/v1/annual.done" ]; then
    pass killed_task_reported
else fail killed_task_reported "rc $rc: $(tr '\n' '|' < "$T/status2.log")"; fi
make -s -C "$O" "${ARGS[@]}" $PIECES OUT="$S2" slurm-resubmit > "$T/resubmit2.log" 2>&1
if grep -q 'stage dcsun: job [0-9]*, task(s) 0$' "$T/resubmit2.log" && ! grep -q 'stage prep\|stage photons\|stage pmmerge\|stage dc:' "$T/resubmit2.log"; then
    pass resubmit_only_that_task
else fail resubmit_only_that_task "$(tr '\n' '|' < "$T/resubmit2.log")"; fi
if scripts/hdslurm wait "$S2" 900 > "$T/wait2.log" 2>&1; then pass resubmitted_run_done
else fail resubmitted_run_done "$(tr '\n' '|' < "$T/wait2.log")"; fi
compare_runs resubmit "$S2"

# ---- bad input is refused before anything is submitted ----
mv "$RUN" "$T/slurm2"
check_fails bad_weather "WEATHER|weather" make -s -C "$O" "${ARGS[@]}" WEATHER="$T/missing.wea" OUT="$T/slurm3" SUBMIT=slurm
if [ ! -e "$T/slurm3/.hdslurm" ]; then pass nothing_submitted; else fail nothing_submitted "$T/slurm3/.hdslurm exists"; fi
exit 0
