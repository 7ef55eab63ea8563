# Outputs named after a device or a FIFO are written in place: the temporary-and-rename of
# regular outputs must never replace them (run as root, a rename onto /dev/null turned the device
# into a regular file, after which every '< /dev/null' read what earlier commands had written).
. test/e2e/lib.sh
genwea -a 52.5 -o -13.4 -m -15 -e 40 -n X "$T/ref.wea"
mkfifo "$T/fifo"
cat "$T/fifo" > "$T/fifo.out" & reader=$!
check fifo_output genwea -a 52.5 -o -13.4 -m -15 -e 40 -n X "$T/fifo"
wait $reader
check fifo_got_everything cmp "$T/ref.wea" "$T/fifo.out"
check fifo_still_fifo test -p "$T/fifo"
check devnull_output genwea -a 52.5 -o -13.4 -m -15 -e 40 -n X /dev/null
check devnull_still_device test -c /dev/null
if ls -a /dev 2>/dev/null | grep -q '^\.null\.hdtmp\.'; then fail no_temporary_beside_devnull "$(ls -a /dev | grep hdtmp)"
else pass no_temporary_beside_devnull; fi
