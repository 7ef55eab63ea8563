#!/usr/bin/env bash
# Benchmark (issue 7): dctimestep with 146 component pictures of 256x256 and
# a full-year 146-patch sky (8760 hourly steps, the reference Chicago MF:1
# year made by Radiance's gendaymtx, from $HELIODON_REF), heliodon vs
# Radiance's dctimestep (RADIANCE_BIN, or a dctimestep on PATH that is not
# ours) in the same run, same output folder.
#
#   case A: one picture per step (-o out/h%04d.hdr), 8760 files;
#   case B: single matrix output: a 1024-row (32x32) DC matrix x the year,
#           -of, one 108 MB file.
#
# Per run: wall, user, sys, peak RSS (GNU time).  Output folder: a tmpfs
# (/dev/shm) when there is one, else $BUILD/bench/dcts; DCTS_OUT=DIR chooses
# (e.g. a folder on disk).  The STREAM-like bandwidth of the machine is
# measured in the same run, the outputs of the two programs are compared.
# usage: BUILD=build RADIANCE_BIN=/path/bin bash test/bench/dctimestep.sh
set -euo pipefail
BUILD=${BUILD:-build}
REF=${HELIODON_REF:-../shared/ref}
B=$BUILD/bench/dcts
mkdir -p "$B"
HD=$BUILD/bin/dctimestep
BD=$BUILD/bench/bench_dctimestep
RAD=${RADIANCE_BIN:+$RADIANCE_BIN/dctimestep}
[ -n "$RAD" ] || RAD=$(command -v dctimestep | grep -v "$BUILD" || true)
sky=$REF/sky/daymtx/chicago_year_mf1.mtx.gz
[ -f "$sky" ] || { echo "SKIP: $sky not found"; exit 0; }
[ -x "$BD" ] || { echo "SKIP: $BD not built (make BUILD=$BUILD bench)"; exit 0; }
[ -x /usr/bin/time ] || { echo "SKIP: GNU time (/usr/bin/time) not found"; exit 0; }
if [ -n "${DCTS_OUT:-}" ]; then O=$DCTS_OUT
elif [ -d /dev/shm ] && [ -w /dev/shm ]; then O=/dev/shm/heliodon-dcts-$$
else O=$B/out; fi
mkdir -p "$O"
trap 'rm -rf "$O/h" "$O/r" "$O/hb" "$O/rb"; [ -z "${DCTS_OUT:-}" ] && rmdir "$O" 2>/dev/null; true' EXIT
fs=$(df -T "$O" | awk 'NR==2{print $2}')

[ -f "$B/c145.hdr" ] || "$BUILD/bench/bench_mkcomponents" "$B" 146 256 256 > /dev/null
[ -f "$B/year.smx" ] || gunzip -c "$sky" > "$B/year.smx"
[ -f "$B/dc1024.mtx" ] || "$BD" mkdc "$B/dc1024.mtx" 146 32 32
echo "date: $(date -u '+%Y-%m-%d %H:%M') UTC  machine: $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')), $(awk '/MemTotal/{printf "%.0f GiB", $2/1048576}' /proc/meminfo), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "output folder: $O ($fs)"
"$BD" stream | tee "$B/stream.txt"
bw=$(awk '/stream_copy_[0-9]+threads/{print $2}' "$B/stream.txt")

# run LABEL OUTDIR STDOUT command...: prints and records wall user sys rss
run() {
    local label=$1 dir=$2 out=$3; shift 3
    rm -rf "$dir"; mkdir -p "$dir"
    /usr/bin/time -f "%e %U %S %M" -o "$B/time.txt" "$@" > "$out" 2> "$B/err_$label.txt" || { echo "$label failed:"; tail -3 "$B/err_$label.txt"; return 1; }
    read -r w u s m < "$B/time.txt"
    printf "%-12s wall %7.2f s  user %7.2f s  sys %6.2f s  cpu %7.2f s  peak RSS %5.0f MB\n" "$label" "$w" "$u" "$s" "$(echo "$u + $s" | bc)" "$(echo "$m / 1024" | bc)"
    echo "$w $u $s $m" > "$B/t_$label.txt"
}
cpu() { awk '{print $2 + $3}' "$B/t_$1.txt"; }
wall() { awk '{print $1}' "$B/t_$1.txt"; }

echo "== case A: 146 pictures 256x256 x 8760 steps, -o one picture per step"
run heliodon_A "$O/h" /dev/null "$HD" -v -o "$O/h/h%04d.hdr" "$B/c%03d.hdr" "$B/year.smx"
grep 'non-black' "$B/err_heliodon_A.txt" | sed 's/^/  /'
nblk=$(sed -n 's/.*(\([0-9]*\) blocks).*/\1/p' "$B/err_heliodon_A.txt")
outbytes=$(du -sb "$O/h" | cut -f1)
echo "  heliodon output: $(ls "$O/h" | wc -l) files, $((outbytes / 1000000)) MB"
if [ -n "$RAD" ] && [ -x "$RAD" ]; then
    run radiance_A "$O/r" /dev/null "$RAD" -o "$O/r/r%04d.hdr" "$B/c%03d.hdr" "$B/year.smx"
    echo "  Radiance output: $(ls "$O/r" | wc -l) files, $(( $(du -sb "$O/r" | cut -f1) / 1000000)) MB"
    echo "  ratio Radiance/heliodon: wall $(echo "scale=1; $(wall radiance_A) / $(wall heliodon_A)" | bc)x, CPU $(echo "scale=1; $(cpu radiance_A) / $(cpu heliodon_A)" | bc)x"
    echo "  values (Jun 21 = steps 4080..4103, and Jan 1 = 0..23): $("$BD" compare "$O/h/h%04d.hdr" "$O/r/r%04d.hdr" 4080 4104)"
    echo "                                                         $("$BD" compare "$O/h/h%04d.hdr" "$O/r/r%04d.hdr" 0 24)"
    rm -rf "$O/r"
else
    echo "  Radiance dctimestep: not found (set RADIANCE_BIN)"
fi
# memory traffic of heliodon's run: the components (146 x 256^2 x 3 floats)
# are read from memory once per block of non-black steps (a block = 256 MiB
# of encoded output, 963 steps), the encoded output is written to the block
# buffer, read by write() and copied into the page cache (3 x output).
awk -v ob="$outbytes" -v w="$(wall heliodon_A)" -v c="$(cpu heliodon_A)" -v bw="$bw" -v nblk="${nblk:-1}" -v nt="$(nproc)" 'BEGIN{
    comp = 146 * 65536 * 12; traffic = nblk * comp + 3 * ob;
    printf "  heliodon memory traffic ~ %.2f GB: per wall second %.2f GB/s = %.0f %% of the %s GB/s STREAM copy (%d threads);\n",
           traffic / 1e9, traffic / 1e9 / w, 100 * traffic / 1e9 / w / bw, bw, nt
    printf "  per CPU second / %d threads (the machine to itself) %.2f GB/s = %.0f %%\n", nt, traffic / 1e9 / (c / nt), 100 * traffic / 1e9 / (c / nt) / bw }'
rm -rf "$O/h"

echo "== case B: DC matrix 1024 x 146 x 8760 steps, -of single matrix output"
run heliodon_B "$O/hb" "$O/hb/h.mtx" "$HD" -of "$B/dc1024.mtx" "$B/year.smx"
if [ -n "$RAD" ] && [ -x "$RAD" ]; then
    run radiance_B "$O/rb" "$O/rb/r.mtx" "$RAD" -of "$B/dc1024.mtx" "$B/year.smx"
    echo "  ratio Radiance/heliodon: wall $(echo "scale=1; $(wall radiance_B) / $(wall heliodon_B)" | bc)x, CPU $(echo "scale=1; $(cpu radiance_B) / $(cpu heliodon_B)" | bc)x"
    echo "  values: $("$BD" comparemtx "$O/hb/h.mtx" "$O/rb/r.mtx")"
fi
