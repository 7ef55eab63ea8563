#!/usr/bin/env bash
# Benchmark: dctimestep folding 146 component pictures of 256x256 with a
# full-year 146-patch sky matrix (the reference Chicago MF:1 year made by
# Radiance's gendaymtx, read from $HELIODON_REF), heliodon vs Radiance's
# dctimestep in the same run when one is found (RADIANCE_BIN or PATH).
# Both write one picture per step (-o) into a scratch folder (compute, RLE
# encoding and writing measured); Radiance's picture mode needs -o for more
# than one step.
set -euo pipefail
BUILD=${BUILD:-build}
REF=${HELIODON_REF:-../shared/ref}
B=$BUILD/bench/dcts
mkdir -p "$B"
HD=$BUILD/bin/dctimestep
RAD=${RADIANCE_BIN:+$RADIANCE_BIN/dctimestep}
[ -n "$RAD" ] || RAD=$(command -v dctimestep | grep -v "$BUILD" || true)
sky=$REF/sky/daymtx/chicago_year_mf1.mtx.gz
[ -f "$sky" ] || { echo "SKIP: $sky not found"; exit 0; }
[ -f "$B/c145.hdr" ] || "$BUILD/bench/bench_mkcomponents" "$B" 146 256 256 > "$B/bw.txt"
gunzip -c "$sky" > "$B/year.smx"
bw=$(awk '{print $2}' "$B/bw.txt")
# a January subset for the side-by-side ratio (Radiance re-reads every picture per step)
"$BUILD/bin/rmtxop" -fa "$B/year.smx" > "$B/year_a.smx"
# keep the first 744 columns (January) of the ascii sky: rows are blocks separated by blank lines
awk 'BEGIN{h=1} h{ if($0 ~ /^NCOLS=/){print "NCOLS=744"} else print; if($0==""){h=0; r=0}; next}
     { n=split($0, a, "\t"); line=""; for(i=1;i<=744 && i<=n;i++) line=line (i>1?"\t":"") a[i]; print line }' "$B/year_a.smx" > "$B/jan.smx"
t() { local s e; rm -rf "$B/out"; mkdir -p "$B/out"; s=$(date +%s.%N); "$@" > /dev/null 2> "$B/err.txt"; e=$(date +%s.%N); echo "$e - $s" | bc; }
echo "date: $(date -u +%Y-%m-%d) machine: $(nproc) cores, $(awk '/MemTotal/{printf "%.0f GiB", $2/1048576}' /proc/meminfo)"
echo "memcpy bandwidth (read+write): $bw GB/s"
th=$(t "$HD" -o "$B/out/h%04d.hdr" "$B/c%03d.hdr" "$B/jan.smx")
echo "heliodon dctimestep, 744 steps (January): $th s"
if [ -n "$RAD" ] && [ -x "$RAD" ]; then
    tr=$(t "$RAD" -o "$B/out/r%04d.hdr" "$B/c%03d.hdr" "$B/jan.smx")
    echo "Radiance dctimestep, 744 steps (January): $tr s  -> ratio $(echo "scale=1; $tr / $th" | bc)x"
else
    echo "Radiance dctimestep: not found (set RADIANCE_BIN)"
fi
ty=$(t "$HD" -o "$B/out/y%04d.hdr" "$B/c%03d.hdr" "$B/year.smx")
nz=$(awk 'BEGIN{h=1} h{if($0=="")h=0; next} {print}' "$B/year_a.smx" | awk -F'\t' '{for(i=1;i<=NF;i++) if($i !~ /^ *0(\.0+e\+00)? 0(\.0+e\+00)? 0(\.0+e\+00)? *$/) nz[i]=1} END{print length(nz)}')
echo "heliodon dctimestep, 8760 steps (full year, $nz non-zero sky columns): $ty s"
# bytes streamed by the fold per non-zero step: the component block is re-read
# once per 32-step sub-block from cache, the output (12 B/pixel) written once.
awk -v nz="$nz" -v t="$ty" -v bw="$bw" 'BEGIN{gb = 146*65536*12*nz/32/1e9 + nz*65536*12/1e9;
    printf "fold traffic ~ %.1f GB -> %.2f GB/s of %s GB/s memcpy\n", gb, gb/t, bw}'
