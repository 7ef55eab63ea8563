# scenes/cfs: the committed XMLs are what the make targets produce (the
# Klems file of the prism film CFS3, the fastest to regenerate), and every
# committed XML loads in checkBSDF with the expected type.
. test/e2e/lib.sh

GB=$(command -v genBSDF)
TA=$(cd "$T" && pwd)
cmdline=$(make -s -n -B -C scenes/cfs GENBSDF="$GB" cfs3_klems.xml 2>/dev/null | grep genBSDF | sed "s|> *cfs3_klems.xml|> '$TA/cfs3_klems.xml'|")
if [ -z "$cmdline" ]; then fail cfs3_reproduced "make -n printed no genBSDF command"
elif (cd scenes/cfs && sh -c "$cmdline") 2> "$T/err" &&
     cmp -s <(sed 2d "$T/cfs3_klems.xml") <(sed 2d scenes/cfs/cfs3_klems.xml); then pass cfs3_reproduced
else fail cfs3_reproduced "$(head -3 "$T/err" | tr '\n' ' ')"; fi

for f in scenes/cfs/cfs*_klems.xml scenes/cfs/cfs*_ttree.xml; do
    [ -f "$f" ] || continue
    b=$(basename "$f" .xml)
    case $b in *klems) want=Klems_Full ;; cfs4_ttree) want=Isotropic_Tensor_Tree ;; *) want=Anisotropic_Tensor_Tree ;; esac
    if checkBSDF "$f" 2>&1 | grep -q "Type: $want"; then pass "load_$b"; else fail "load_$b" "not $want"; fi
done
