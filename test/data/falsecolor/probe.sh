#!/bin/bash
# Samples Radiance 6.1's falsecolor palettes "def" and "tbo" on a ramp of
# 1025 values v = 0, 1/1024 .. 1, with Radiance's own programs (not part of
# heliodon's build or tests; run once beside a Radiance installation):
#   PATH=/path/to/radiance/bin:$PATH RAYPATH=.:/path/to/radiance/lib bash probe.sh
# Each channel value f(v) is read back in three pieces so that the 8-bit
# mantissas of the RGBE output lose nothing that matters:
#   floor(256 f)/256,  floor(256 frac(256 f))/256,  frac(65536 f)
# each alone in the red channel of a 1 x 1025 picture (falsecolor pads it
# to 3 columns: no run-length encoding at that width, so the bytes are read
# directly), and combined as
#   f = a + b/256 + c/65536  (c taken at the middle of its mantissa step:
#   |error| < 2^-9/65536 + rounding, below 1e-7).
# Output: samples_<pal>.txt with the columns v red green blue (%.9f).
set -euo pipefail
N=${PROBE_N:-1025}      # samples (PROBE_N overrides, for checks between the stored samples)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pcomb -x 1 -y $N -e 'ro=1;go=1;bo=1' > "$tmp/ramp.hdr"
decode() {  # picture -> the first pixel of each row, top row first ((red byte + mid) * 2^(exp-136))
    # falsecolor pads the picture to 3 columns: rows of 12 bytes after the resolution line
    local line off; line=$(grep -a -m1 '^-Y ' "$1"); off=$(grep -abn -m1 '^-Y ' "$1" | cut -d: -f2)
    tail -c +$((off + ${#line} + 2)) "$1" | od -An -v -tu1 -w12 |
        awk -v mid="$2" '{ if ($4 == 0) { print 0; next }
                          printf "%.12g\n", ($1 + mid) * 2 ^ ($4 - 136) }'
}
for pal in def tbo; do
    cols=()
    for ch in red grn blu; do
        f="${pal}_${ch}(($N-1-y)/($N-1))"       # y counts from the bottom; rows are written top first
        falsecolor -i "$tmp/ramp.hdr" -lw 0 -lh 0 -r "floor(256*$f)/256" -g 0 -b 0 > "$tmp/a.hdr"
        falsecolor -i "$tmp/ramp.hdr" -lw 0 -lh 0 -r "floor(256*frac(256*$f))/256" -g 0 -b 0 > "$tmp/b.hdr"
        falsecolor -i "$tmp/ramp.hdr" -lw 0 -lh 0 -r "frac(65536*$f)" -g 0 -b 0 > "$tmp/c.hdr"
        paste <(decode "$tmp/a.hdr" 0) <(decode "$tmp/b.hdr" 0) <(decode "$tmp/c.hdr" .5) |
            awk '{ printf "%.9f\n", $1 + $2 / 256 + $3 / 65536 }' > "$tmp/$ch"
        cols+=("$tmp/$ch")
    done
    seq 0 $((N - 1)) | awk -v n=$((N - 1)) '{ printf "%.9f\n", $1 / n }' | paste - "${cols[@]}" |
        tr '\t' ' ' > "samples_$pal.txt"
done
