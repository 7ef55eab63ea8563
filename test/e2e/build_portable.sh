#!/usr/bin/env bash
# The sources with CPU-specific kernels also build without them (-Werror),
# as on a CPU family other than x86-64: the photon-map selection kernels
# switched off with PM_NOVEC (portable C only).  Syntax and warnings only.
. test/e2e/lib.sh
CC=${CC:-cc}
command -v "$CC" >/dev/null 2>&1 || { skip novec "no C compiler ($CC)"; exit 0; }
check pmap_gather_novec "$CC" -std=c11 -Wall -Wextra -Werror -pthread -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE \
    -Iinclude -Isrc -DPM_NOVEC -fsyntax-only src/pmap_gather.c
