# make install PREFIX=...: programs, man pages, headers, static library and a
# pkg-config file that lets a program link against libheliodon.
. test/e2e/lib.sh
P=$T/prefix
if make -s --no-print-directory install BUILD="${BUILD:-build}" PREFIX="$P" > "$T/install.log" 2>&1; then pass make_install
else fail make_install "$(tail -3 "$T/install.log")"; exit 0; fi
nbin=$(( $(ls tools/*.c | wc -l) + $(ls scripts | wc -l) )); ninst=$(ls "$P/bin" | wc -l)
if [ "$nbin" -eq "$ninst" ]; then pass all_programs_installed; else fail all_programs_installed "$ninst of $nbin"; fi
missing=""
for t in tools/*.c; do n=$(basename "$t" .c); [ -f "$P/share/man/man1/$n.1" ] || missing="$missing $n"; done
if [ -z "$missing" ]; then pass man_page_per_program; else fail man_page_per_program "no man page for:$missing"; fi
printf '#include <heliodon/matrix.h>\nint main(void){hd_matrix m; hd_matrix_init(&m); return hd_matrix_alloc(&m,2,3,3) != HD_OK;}\n' > "$T/use.c"
export PKG_CONFIG_PATH="$P/lib/pkgconfig"
if cc -std=c11 $(pkg-config --cflags heliodon) "$T/use.c" -o "$T/use" $(pkg-config --static --libs heliodon) 2> "$T/cc.log" && "$T/use"; then
    pass pkgconfig_link; else fail pkgconfig_link "$(head -3 "$T/cc.log")"; fi
# only the public API is installed (include/heliodon/), and each installed
# header compiles alone against the installed tree: none includes a private
# header of src/ (docs/design.md, Layout)
bad=""
for h in "$P"/include/heliodon/*.h; do
    printf '#include <heliodon/%s>\nint hd_install_probe;\n' "$(basename "$h")" > "$T/h.c"
    cc -std=c11 -Wall -Werror -fsyntax-only -I"$P/include" "$T/h.c" 2>> "$T/hcc.log" || bad="$bad $(basename "$h")"
done
for h in src/*.h; do [ -f "$P/include/heliodon/$(basename "$h")" ] && bad="$bad private:$(basename "$h")"; done
nh=$(ls include/heliodon/*.h | wc -l); ni=$(ls "$P"/include/heliodon/*.h | wc -l)
if [ -z "$bad" ] && [ "$nh" -eq "$ni" ]; then pass public_headers_standalone
else fail public_headers_standalone "$ni of $nh installed; failing:$bad $(head -2 "$T/hcc.log")"; fi
# every installed header is API: a program of tools/ includes it, directly or
# through other installed headers (internal seams are private headers of src/)
api=$(grep -ho '"heliodon/[a-z_]*\.h"' tools/*.c | sort -u | tr -d '"' | sed 's|heliodon/||')
while :; do
    more=$(for b in $api; do grep -ho '#include "\(heliodon/\)\?[a-z_]*\.h"' "include/heliodon/$b" 2>/dev/null; done |
           sed 's|#include "||; s|"||; s|heliodon/||' | cat - <(printf '%s\n' $api) | sort -u)
    [ "$more" = "$(printf '%s\n' $api | sort -u)" ] && break
    api=$more
done
notapi=""
for h in include/heliodon/*.h; do printf '%s\n' $api | grep -qx "$(basename "$h")" || notapi="$notapi $(basename "$h")"; done
if [ -z "$notapi" ]; then pass installed_headers_are_api
else fail installed_headers_are_api "not reached from any program of tools/:$notapi"; fi
# the library .cal files (lib/) go to PREFIX/lib/ray, where RAYPATH finds them
AP=$(cd "$P" && pwd)
ncal=$(ls lib/*.cal | wc -l); ninst=$(ls "$AP/lib/ray/"*.cal 2>/dev/null | wc -l)
if [ "$ncal" -eq "$ninst" ] && [ "$(cd /tmp && RAYPATH="$AP/lib/ray" "$AP/bin/rcalc" -n -f reinhartb.cal -e '$1=Nrbins')" = 145 ]; then
    pass cal_library_installed; else fail cal_library_installed "$ninst of $ncal .cal files in $P/lib/ray"; fi
