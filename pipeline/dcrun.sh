#!/bin/sh
# dcrun.sh DIR K N NREC UNIT TIMINGS NAME COMMAND
# Run one daylight-coefficient command of the pipeline (rcontrib writing -o patterns relative to
# its folder) in a fresh folder, then rename the folder to its final name:
#   K = all   the whole output into DIR
#   K = 0..N-1  piece K of N into DIR.p/K: COMMAND runs with HD_R="-R first count", records
#             cut at multiples of UNIT (image rows; 1 for sensor points); rcmerge -d joins them.
# Every run works in a folder of its own with the same relative -o, so the headers of the pieces
# and of the whole run are the same (rcontrib(1), PIECES).  NAME is timed into TIMINGS.
set -e
dir=$1 k=$2 n=$3 nrec=$4 unit=$5 tf=$6 name=$7 cmd=$8
HD_R=
if [ "$k" != all ]; then
    rows=$((nrec / unit))
    if [ "$n" -gt "$rows" ]; then
        echo "heliodon-pipeline: DC_PIECES=$n: more pieces than the $rows rows of $dir" >&2; exit 1
    fi
    a=$((k * rows / n * unit)); b=$(((k + 1) * rows / n * unit))
    HD_R="-R $a $((b - a))"
    dir=$dir.p/$k
    name=${name}_p$k
fi
export HD_R
rm -rf "$dir.tmp"
mkdir -p "$dir.tmp"
stage=$(cd "$(dirname "$0")" && pwd)/stage.sh   # the pipeline's one stage timer
(cd "$dir.tmp" && "$stage" "$tf" "$name" sh -c "$cmd")
rm -rf "$dir"
mv "$dir.tmp" "$dir"
