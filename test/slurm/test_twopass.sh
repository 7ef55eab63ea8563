#!/usr/bin/env bash
# The two-pass operated shade (FS2's schedule; CONFIG=fs2x, the stand-in without BSDF tracing)
# submitted to a one-machine SLURM cluster: the open and the closed pass as their own stages
# (open_*, closed_*), DCs in 2 record pieces, compositions in 2 hour pieces, then the schedule and
# the report; every output byte-identical to the one-machine run in the same folder (timings and
# the photon maps' text headers aside, as test_pipeline.sh).
. "$(dirname "$0")/../e2e/lib.sh"
ROOT=$(pwd)
T=$(cd "$T" && pwd)
. "$(dirname "$0")/lib.sh"
export PATH SOURCE_DATE_EPOCH=1700000000
unset MAKEFLAGS MFLAGS MAKELEVEL
O=$ROOT/scenes/office
izmir_wea "$T/w.wea" '3 21 1.5 0 0' '3 21 8.5 300 60' '3 21 10.5 820 110' '3 21 14.5 780 130' '12 21 11.5 700 90'
ARGS=(WEATHER="$T/w.wea" CONFIG=fs2x VIEW=v1 RES=16 MF=1 PHOTONS=30k BANDWIDTH=50 SHADE_LIMIT=0.33 NPROC=1
      SKY_OPTS="-ab 1 -ad 64 -lw 1e-3" FEN_OPTS="-ab 1 -ad 64 -lw 1e-3" FENSUN_OPTS="-ab 1 -ad 16 -lw 1e-3" GROUNDPTS=128)
RUN=$T/run
if make -s -C "$O" "${ARGS[@]}" OUT="$RUN" > "$T/local.log" 2>&1 && mv "$RUN" "$T/local"; then pass local_run
else fail local_run "$(grep -v 'no emission' "$T/local.log" | tail -3 | tr '\n' ' ')"; exit 0; fi
if make -s -C "$O" "${ARGS[@]}" OUT="$RUN" SUBMIT=slurm SLURM_MEM=500M DC_PIECES=2 HOUR_PIECES=2 > "$T/submit.log" 2>&1; then
    pass submit
else fail submit "$(tail -3 "$T/submit.log" | tr '\n' ' ')"; exit 0; fi
if grep -q '^open_prep 1 - ' "$RUN/slurm.plan" && grep -q '^closed_prep 1 open_prep ' "$RUN/slurm.plan" &&
   grep -q '^open_compose 2 ' "$RUN/slurm.plan" && grep -q '^report 1 open_annual,closed_annual ' "$RUN/slurm.plan"
then pass plan_two_passes; else fail plan_two_passes "$(cut -c1-30 "$RUN/slurm.plan" | tr '\n' '|')"; fi
if scripts/hdslurm wait "$RUN" 900 > "$T/wait.log" 2>&1; then pass all_tasks_done
else fail all_tasks_done "$(tr '\n' '|' < "$T/wait.log")"; fi
( cd "$T/local" && find . -type f | sort ) > "$T/f.local"
( cd "$RUN" && find . -type f ! -path './.hdslurm/*' ! -path '*/pm/*' ! -path '*.p/*' ! -path '*/compose.h/*' \
    ! -name slurm.plan | sort ) > "$T/f.slurm"
if cmp -s "$T/f.local" "$T/f.slurm"; then pass same_files
else fail same_files "$(diff "$T/f.local" "$T/f.slurm" | head -5 | tr '\n' ' ')"; fi
bad=""
while read -r f; do
    case $f in
    ./timings.txt|*/timings.txt|./schedule_time.txt|./report/*) continue ;;
    */summary.txt|*/notes.txt) cmp -s <(grep -v '_seconds:' "$T/local/$f") <(grep -v '_seconds:' "$RUN/$f") || bad="$bad $f" ;;
    */sun.cpm) cmp -s <(sed '1,/^$/d' "$T/local/$f") <(sed '1,/^$/d' "$RUN/$f") || bad="$bad $f" ;;
    *) cmp -s "$T/local/$f" "$RUN/$f" || bad="$bad $f" ;;
    esac
done < "$T/f.local"
if [ -z "$bad" ]; then pass byte_identical; else fail byte_identical "differ:$(echo $bad | cut -c1-300)"; fi
if awk -F, 'NR > 1 {n[$9]++} END {exit !(n[0] >= 1 && n[1] >= 1)}' "$RUN/v1/schedule.csv"; then pass both_states
else fail both_states "$(tr '\n' '|' < "$RUN/v1/schedule.csv")"; fi
exit 0
