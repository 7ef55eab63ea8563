#!/usr/bin/env bash
# hdslurm on a real one-machine SLURM cluster (slurmctld + slurmd + munged
# started here, in a temporary folder, and stopped at the end): a three-stage
# plan of array jobs with afterok dependencies, the merge identical to the
# same plan run without SLURM, one task killed with scancel and only that task
# resubmitted, status/exit codes, and plans that are refused.
. "$(dirname "$0")/../e2e/lib.sh"
here=$(cd "$(dirname "$0")" && pwd)
HDSLURM=${HDSLURM:-$here/../../scripts/hdslurm}
. "$(dirname "$0")/lib.sh"

W=$T/work; mkdir -p "$W"
# each piece depends on its task index only; the merge concatenates in order
cat > "$T/plan" <<'PLAN'
# name  tasks after  cpus mem   command
pieces  4     -      1    100M  sleep $((HD_TASK % 2 * 6)); seq $((HD_TASK * 10)) $((HD_TASK * 10 + 9)) > piece.$HD_TASK.tmp && mv piece.$HD_TASK.tmp piece.$HD_TASK
merge   1     pieces 1    100M  cat piece.0 piece.1 piece.2 piece.3 > merged.txt
report  1     merge  1    100M  awk '{s += $1} END {print NR, s}' merged.txt > report.txt
PLAN
# the same plan without a scheduler, for the byte comparison
L=$T/local; mkdir -p "$L"
( cd "$L" && for t in 0 1 2 3; do seq $((t * 10)) $((t * 10 + 9)) > piece.$t; done
  cat piece.0 piece.1 piece.2 piece.3 > merged.txt; awk '{s += $1} END {print NR, s}' merged.txt > report.txt )

check submit "$HDSLURM" submit "$T/plan" "$W"
if [ "$(awk 'END {print NR}' "$W/.hdslurm/jobs.tsv")" = 3 ]; then pass three_jobs; else fail three_jobs "$(cat "$W/.hdslurm/jobs.tsv")"; fi
"$HDSLURM" wait "$W" 120 > "$T/wait.out" 2>&1; rc=$?
if [ $rc -eq 0 ]; then pass wait_all_done; else fail wait_all_done "rc $rc: $(cat "$T/wait.out")"; fi
check merged_identical cmp "$W/merged.txt" "$L/merged.txt"
check report_identical cmp "$W/report.txt" "$L/report.txt"
check status_done "$HDSLURM" status "$W"

# kill one task of the first stage: the later stages can never start
W2=$T/work2; mkdir -p "$W2"
"$HDSLURM" submit "$T/plan" "$W2" > /dev/null
j=$(awk '$1 == "pieces" {print $2}' "$W2/.hdslurm/jobs.tsv")
for i in $(seq 50); do   # wait until task 1 runs (it sleeps 6 s: 2 s lost the race on a loaded machine), then cancel it
    squeue -h -r -j "$j" -t R -o '%K' 2>/dev/null | grep -qx 1 && break; sleep 0.2
done
scancel "${j}_1"
for i in $(seq 100); do [ -e "$W2/.hdslurm/done/pieces.3" ] && break; sleep 0.2; done
sleep 1
"$HDSLURM" status "$W2" > "$T/st.out" 2>&1; rc=$?
if [ $rc -eq 3 ] && awk '$1 == "pieces" && $3 == 3 && $5 == "1" {ok = 1} END {exit !ok}' "$T/st.out"; then
    pass status_reports_killed_task
else fail status_reports_killed_task "rc $rc: $(cat "$T/st.out")"; fi
"$HDSLURM" resubmit "$W2" > "$T/re.out" 2>&1
if grep -q 'stage pieces: job [0-9]*, task(s) 1,' "$T/re.out" || grep -q 'stage pieces: job [0-9]*, task(s) 1$' "$T/re.out"; then
    pass resubmit_only_killed_task
else fail resubmit_only_killed_task "$(cat "$T/re.out")"; fi
"$HDSLURM" wait "$W2" 120 > "$T/wait2.out" 2>&1; rc=$?
if [ $rc -eq 0 ]; then pass resubmit_completes; else fail resubmit_completes "rc $rc: $(cat "$T/wait2.out")"; fi
check resubmit_merged_identical cmp "$W2/merged.txt" "$L/merged.txt"
check resubmit_report_identical cmp "$W2/report.txt" "$L/report.txt"
# the done tasks ran once: one log line per task start
n=$(cat "$W2/.hdslurm/done/"pieces.* | wc -l)
if [ "$n" = 4 ]; then pass four_done_markers; else fail four_done_markers "$n"; fi
"$HDSLURM" resubmit "$W2" > "$T/re2.out" 2>&1
check nothing_to_resubmit grep -q "nothing to resubmit" "$T/re2.out"

# plans that are refused before anything is submitted
printf 'a 2 - 1 1G true\nb 1 c 1 1G true\n' > "$T/bad1"
check_fails plan_unknown_after "bad1:2: stage 'b' comes after 'c'" "$HDSLURM" submit "$T/bad1" "$T/w3"
printf 'a 0 - 1 1G true\n' > "$T/bad2"
check_fails plan_zero_tasks "bad2:1: task count '0'" "$HDSLURM" submit "$T/bad2" "$T/w3"
printf 'a 1 - 1 1G true\na 1 - 1 1G true\n' > "$T/bad3"
check_fails plan_duplicate "bad3:2: stage 'a' defined twice" "$HDSLURM" submit "$T/bad3" "$T/w3"
printf 'a 1 - 1 lots true\n' > "$T/bad4"
check_fails plan_memory "bad4:1: memory 'lots'" "$HDSLURM" submit "$T/bad4" "$T/w3"
printf 'a 1 -\n' > "$T/bad5"
check_fails plan_short_line "bad5:1: expected NAME TASKS AFTER CPUS MEM COMMAND" "$HDSLURM" submit "$T/bad5" "$T/w3"
check_fails status_no_plan "no plan submitted here" "$HDSLURM" status "$T"
exit 0
