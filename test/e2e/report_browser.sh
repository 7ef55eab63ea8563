#!/bin/bash
# The HTML report renders in a real headless browser (Chromium) with no broken references:
# every <img> has loaded with a non-zero natural size (checked in the DOM after load), and a
# screenshot is produced.  Installs the Debian package "chromium" if it is missing and we are
# root (the lead's tools/setup-deps can call:  test/e2e/report_browser.sh --install).
if [ "${1:-}" = "--install" ]; then
    command -v chromium >/dev/null 2>&1 && exit 0
    [ "$(id -u)" = 0 ] || { echo "report_browser: run as root: apt-get install -y chromium" >&2; exit 1; }
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null || exit 1
    exit 0
fi
. test/e2e/lib.sh
T=$(cd "$T" && pwd)
if ! command -v chromium >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        DEBIAN_FRONTEND=noninteractive timeout 600 apt-get install -y -qq chromium > "$T/apt.log" 2>&1 || true
    fi
fi
if ! command -v chromium >/dev/null 2>&1; then
    skip render "chromium not installed (Debian package chromium; test/e2e/report_browser.sh --install)"
    exit 0
fi
# a small annual data set: a synthetic year of DGP values and two false-colour hours
awk 'BEGIN {
    print "hour,Ev,DGP,DGI,UGR,nsources,DGP_class,DGI_class,shade"
    for (d = 0; d < 365; d++) for (h = 7; h < 18; h++) {
        x = (h - 12.5) / 5; s = cos(2 * 3.14159265 * (d - 355) / 365)
        dgp = 0.25 + 0.2 * s * (1 - x * x); dgi = 10 + 15 * s * (1 - x * x)
        printf "%d.5,%.1f,%.4f,%.3f,%.3f,1,x,x,%d\n", d * 24 + h, 2000 + 3000 * s, dgp, dgi, dgi + 5, (dgp >= 0.4 ? 1 : 0)
    } }' > "$T/a.csv"
mkpic() {  # mkpic out.hdr scale: a 32x32 fisheye-ish test picture with a VIEW line
    { printf '#?RADIANCE\nVIEW= -vta -vp 1 2.2 1.2 -vd 1 0 0 -vu 0 0 1 -vh 180 -vv 180\nHOUR= 1906 3 21 10.500\nFORMAT=32-bit_rle_rgbe\n\n-Y 32 +X 32\n'
      awk -v s="$2" 'BEGIN { for (y = 0; y < 32; y++) for (x = 0; x < 32; x++) printf "%c%c%c%c", 128, 128, 128, 129 + int(s * (x + y) / 64) }'
    } > "$1"
}
mkpic "$T/h1.hdr" 4
mkpic "$T/h2.hdr" 8
printf 'weather = synthetic\nresolution = 32 x 32\n' > "$T/p.txt"
printf 'gensuns 0.1\npmcompose 12.3\n' > "$T/t.txt"
check make_report cbdmreport -c "$T/a.csv" -o "$T/rep" -p "$T/p.txt" -T "$T/t.txt" "$T/h1.hdr" "$T/h2.hdr"
# the page, with a script appended that reports every image's load state into the DOM
cp "$T/rep/index.html" "$T/rep/check.html"
cat >> "$T/rep/check.html" <<'JS'
<script>
window.addEventListener('load', function () {
  var imgs = document.images, bad = [];
  for (var i = 0; i < imgs.length; i++)
    if (!imgs[i].complete || imgs[i].naturalWidth === 0) bad.push(imgs[i].getAttribute('src'));
  var p = document.createElement('p');
  p.id = 'imgcheck';
  p.textContent = 'IMGCHECK images=' + imgs.length + ' broken=' + bad.length + ' [' + bad.join(' ') + ']';
  document.body.appendChild(p);
});
</script>
JS
CH="chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking --disable-component-update --disable-sync"
U=$(mktemp -d)
timeout 120 $CH --user-data-dir="$U" --virtual-time-budget=5000 --dump-dom "file://$T/rep/check.html" > "$T/dom.html" 2> "$T/chromium.err"
line=$(grep -o 'id="imgcheck">IMGCHECK[^<]*' "$T/dom.html")
echo "$line" >&2
case "$line" in
    *"images=0 "*|"") fail dom "no image check in the DOM: $(tail -2 "$T/chromium.err" | tr '\n' ' ')" ;;
    *"broken=0 "*) pass dom ;;
    *) fail dom "$line" ;;
esac
n=$(echo "$line" | sed 's/.*images=\([0-9]*\).*/\1/')
if [ "${n:-0}" -ge 8 ]; then pass image_count; else fail image_count "expected >= 8 images, got $n"; fi
rm -rf "$U"; U=$(mktemp -d)
timeout 120 $CH --user-data-dir="$U" --window-size=1100,3000 --screenshot="$T/shot.png" "file://$T/rep/index.html" > /dev/null 2>&1
rm -rf "$U"
check screenshot cbdmreport -check "$T/shot.png"
