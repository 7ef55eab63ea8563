# heliodon — build, test and install.
#   make            build the library and every program into build/
#   make check      run every test (unit, end-to-end); prints "N passed, N failed"
#   make check-asan unit tests, fuzz regression inputs and the readers'
#                   end-to-end tests under AddressSanitizer + UBSan
#   make fuzz       fuzz every reader with clang's libFuzzer (docs/fuzz.md;
#                   FUZZ_SECONDS per harness, default 20)
#   make check-slurm  tests on a one-machine SLURM cluster (installs slurm-wlm
#                   and munge as root, starts and stops its own daemons)
#   make demo       run the main job
#   make bench      run the benchmarks in test/bench (not part of check)
#   make compare-builds REV=main [BENCH="rtrace mkpmap"]  speed of this tree
#                   against revision REV, same run (docs/benchmarks.md)
#   make install PREFIX=/usr/local   (programs, library, man pages, and the annual pipeline
#                   in $(PREFIX)/share/heliodon/heliodon.mk)
# Sources are found by wildcard: a new src/*.c joins the library, a new
# tools/NAME.c becomes program NAME, a new test/unit/test_*.c a unit test.

PREFIX  ?= /usr/local
CC      ?= cc
BUILD   ?= build
OPT     ?= -O2 -g
SAN     ?=
EXR_CFLAGS := $(shell pkg-config --cflags OpenEXR 2>/dev/null || echo -I/usr/include/OpenEXR)
CPPFLAGS += -Iinclude -Isrc -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE
CFLAGS  ?=
CFLAGS  += -std=c11 -Wall -Wextra -Werror -pthread -MMD -MP $(OPT) $(SAN)
LDFLAGS += -pthread $(SAN)
LDLIBS  += -lembree3 -lOpenEXRCore -lexpat -lz -lm

SRC     := $(wildcard src/*.c)
OBJ     := $(SRC:src/%.c=$(BUILD)/obj/%.o)
LIB     := $(BUILD)/libheliodon.a
TOOLSRC := $(wildcard tools/*.c)
BINS    := $(TOOLSRC:tools/%.c=$(BUILD)/bin/%)
UNITSRC := $(wildcard test/unit/test_*.c)
UNITS   := $(UNITSRC:test/unit/%.c=$(BUILD)/test/%)
FUZZSRC := $(wildcard test/fuzz/fuzz_*.c)
FUZZBINS:= $(FUZZSRC:test/fuzz/%.c=$(BUILD)/fuzz/%)
BENCHSRC:= $(wildcard test/bench/*.c)
BENCHES := $(BENCHSRC:test/bench/%.c=$(BUILD)/bench/%)
DEPSTAMP:= $(BUILD)/.deps-ok

.PHONY: all deps check check-unit check-e2e check-asan check-slurm fuzz demo bench compare-builds install clean
all: $(DEPSTAMP) $(LIB) $(BINS)

deps: $(DEPSTAMP)
$(DEPSTAMP): tools/setup-deps
	@tools/setup-deps
	@mkdir -p $(@D) && touch $@

$(BUILD)/obj/%.o: src/%.c | $(DEPSTAMP)
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(EXR_CFLAGS) $(CFLAGS) -c $< -o $@

# the .cal library: installed under $(PREFIX)/lib/ray; the source tree's
# lib/ is searched after it when RAYPATH is unset (tests, uninstalled use)
$(BUILD)/obj/cal.o: CPPFLAGS += -DHD_CAL_LIBDIR='"$(PREFIX)/lib/ray"' -DHD_CAL_SRCLIB='"$(CURDIR)/lib"'

$(LIB): $(OBJ)
	@rm -f $@
	ar rcs $@ $^

$(BUILD)/bin/%: tools/%.c $(LIB)
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(CFLAGS) $< -o $@ $(LDFLAGS) $(LIB) $(LDLIBS)

$(BUILD)/test/%: test/unit/%.c test/unit/hd_test.h $(LIB)
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) -Itest/unit $(EXR_CFLAGS) $(CFLAGS) $< -o $@ $(LDFLAGS) $(LIB) $(LDLIBS)

# Fuzz harnesses driven over files (test/fuzz/driver.c): the regression
# inputs run in make check; `make fuzz` links the same harnesses with libFuzzer.
$(BUILD)/fuzz/driver.o: test/fuzz/driver.c test/fuzz/fuzz.h | $(DEPSTAMP)
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILD)/fuzz/%: test/fuzz/%.c test/fuzz/fuzz.h $(BUILD)/fuzz/driver.o $(LIB)
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(EXR_CFLAGS) $(CFLAGS) $< $(BUILD)/fuzz/driver.o -o $@ $(LDFLAGS) $(LIB) $(LDLIBS)

$(BUILD)/bench/%: test/bench/%.c $(LIB)
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(EXR_CFLAGS) $(CFLAGS) $< -o $@ $(LDFLAGS) $(LIB) $(LDLIBS)

check: all $(UNITS) $(FUZZBINS)
	@BUILD=$(BUILD) test/run-tests.sh unit fuzz e2e

check-unit: all $(UNITS)
	@BUILD=$(BUILD) test/run-tests.sh unit

check-e2e: all
	@BUILD=$(BUILD) test/run-tests.sh e2e

# Under AddressSanitizer and UndefinedBehaviorSanitizer, in a build tree of
# their own: the unit tests, the fuzz regression inputs, and the end-to-end
# tests of the readers (ASAN_E2E, with the sanitized programs on PATH; leak
# checks there are off: programs exit without freeing what they hold).
ASAN_E2E ?= scene_errors picture_tools exr_tools rmtxop dctimestep sky_genwea \
            pmap_tools bsdf_tools pipeline_errors rcontrib_recover_c0
check-asan: $(DEPSTAMP)
	@$(MAKE) --no-print-directory BUILD=build-asan OPT="-O1 -g -fno-omit-frame-pointer" \
	    SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" all \
	    $(UNITSRC:test/unit/%.c=build-asan/test/%) $(FUZZSRC:test/fuzz/%.c=build-asan/fuzz/%)
	@ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1 \
	    BUILD=build-asan test/run-tests.sh unit fuzz
	@ASAN_OPTIONS=detect_leaks=0:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1 \
	    E2E_ONLY="$(ASAN_E2E)" BUILD=build-asan test/run-tests.sh e2e

# Coverage-guided fuzzing of every reader (docs/fuzz.md): the library and
# the harnesses built with clang + libFuzzer + ASan + UBSan in build-fuzz/,
# corpora seeded from the project's files, each harness run FUZZ_SECONDS;
# crashes are collected in build-fuzz/crashes/.  Needs clang (installed by
# tools/setup-deps --fuzz); make check does not.
FUZZ_CC      ?= clang-14
FUZZ_SECONDS ?= 20
FUZZ_SAN     := -fsanitize=address,undefined -fno-sanitize-recover=undefined
fuzz: all
	@tools/setup-deps --fuzz
	@$(MAKE) --no-print-directory BUILD=build-fuzz CC=$(FUZZ_CC) OPT="-O1 -g -fno-omit-frame-pointer" \
	    SAN="-fsanitize=fuzzer-no-link $(FUZZ_SAN)" build-fuzz/libheliodon.a
	@mkdir -p build-fuzz/bin
	@for h in $(FUZZSRC:test/fuzz/%.c=%); do \
	    $(FUZZ_CC) $(CPPFLAGS) $(EXR_CFLAGS) -std=c11 -Wall -Wextra -Werror -pthread -O1 -g \
	        -fno-omit-frame-pointer -fsanitize=fuzzer $(FUZZ_SAN) test/fuzz/$$h.c -o build-fuzz/bin/$$h \
	        build-fuzz/libheliodon.a $(LDLIBS) || exit 1; \
	done
	@BUILD=$(BUILD) FUZZ_SECONDS=$(FUZZ_SECONDS) test/fuzz/run-fuzz.sh $(FUZZ)

check-slurm: all
	@tools/setup-deps --slurm
	@BUILD=$(BUILD) test/run-tests.sh slurm

demo: all
	@BUILD=$(BUILD) scenes/demo.sh

bench: all $(BENCHES)
	@BUILD=$(BUILD) test/bench/run-bench.sh

compare-builds: all
	@BUILD=$(BUILD) test/bench/compare_builds.sh $(if $(ROUNDS),-r $(ROUNDS)) $(REV) $(BENCH)

install: all
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig \
	    $(DESTDIR)$(PREFIX)/include/heliodon $(DESTDIR)$(PREFIX)/share/man/man1
	install -m 755 $(BINS) $(DESTDIR)$(PREFIX)/bin/
	install -m 755 scripts/hdslurm $(DESTDIR)$(PREFIX)/bin/
	install -m 644 $(LIB) $(DESTDIR)$(PREFIX)/lib/
	install -m 644 include/heliodon/*.h $(DESTDIR)$(PREFIX)/include/heliodon/
	install -m 644 docs/man/*.1 $(DESTDIR)$(PREFIX)/share/man/man1/
	install -d $(DESTDIR)$(PREFIX)/share/heliodon $(DESTDIR)$(PREFIX)/share/man/man7
	install -m 644 pipeline/*.mk pipeline/*.awk pipeline/*.rad $(DESTDIR)$(PREFIX)/share/heliodon/
	install -m 755 pipeline/*.sh $(DESTDIR)$(PREFIX)/share/heliodon/
	install -m 644 docs/man/*.7 $(DESTDIR)$(PREFIX)/share/man/man7/
	install -d $(DESTDIR)$(PREFIX)/lib/ray
	install -m 644 lib/*.cal lib/lamp.tab $(DESTDIR)$(PREFIX)/lib/ray/
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@LIBS@|$(LDLIBS)|g' \
	    -e 's|@VERSION@|$(shell sed -n 's/^#define HD_VERSION "\(.*\)"/\1/p' include/heliodon/common.h)|g' \
	    heliodon.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/heliodon.pc

clean:
	rm -rf build build-asan build-fuzz

-include $(OBJ:.o=.d) $(BINS:%=%.d) $(UNITS:%=%.d) $(FUZZBINS:%=%.d) $(BUILD)/fuzz/driver.d
