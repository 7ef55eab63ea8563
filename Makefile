# heliodon — build, test and install.
#   make            build the library and every program into build/
#   make check      run every test (unit, end-to-end); prints "N passed, N failed"
#   make check-asan unit tests under AddressSanitizer + UBSan
#   make demo       run the main job
#   make bench      run the benchmarks in test/bench (not part of check)
#   make install PREFIX=/usr/local
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
BENCHSRC:= $(wildcard test/bench/*.c)
BENCHES := $(BENCHSRC:test/bench/%.c=$(BUILD)/bench/%)
DEPSTAMP:= $(BUILD)/.deps-ok

.PHONY: all deps check check-unit check-e2e check-asan demo bench install clean
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

$(BUILD)/bench/%: test/bench/%.c $(LIB)
	@mkdir -p $(@D)
	$(CC) $(CPPFLAGS) $(EXR_CFLAGS) $(CFLAGS) $< -o $@ $(LDFLAGS) $(LIB) $(LDLIBS)

check: all $(UNITS)
	@BUILD=$(BUILD) test/run-tests.sh unit e2e

check-unit: all $(UNITS)
	@BUILD=$(BUILD) test/run-tests.sh unit

check-e2e: all
	@BUILD=$(BUILD) test/run-tests.sh e2e

# Unit tests under AddressSanitizer and UndefinedBehaviorSanitizer, in a
# build tree of their own.
check-asan: $(DEPSTAMP)
	@$(MAKE) --no-print-directory BUILD=build-asan OPT="-O1 -g -fno-omit-frame-pointer" \
	    SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" all \
	    $(UNITSRC:test/unit/%.c=build-asan/test/%)
	@ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1 \
	    BUILD=build-asan test/run-tests.sh unit

demo: all
	@BUILD=$(BUILD) scenes/demo.sh

bench: all $(BENCHES)
	@BUILD=$(BUILD) test/bench/run-bench.sh

install: all
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig \
	    $(DESTDIR)$(PREFIX)/include/heliodon $(DESTDIR)$(PREFIX)/share/man/man1
	install -m 755 $(BINS) $(DESTDIR)$(PREFIX)/bin/
	install -m 644 $(LIB) $(DESTDIR)$(PREFIX)/lib/
	install -m 644 include/heliodon/*.h $(DESTDIR)$(PREFIX)/include/heliodon/
	install -m 644 docs/man/*.1 $(DESTDIR)$(PREFIX)/share/man/man1/
	install -d $(DESTDIR)$(PREFIX)/lib/ray
	install -m 644 lib/*.cal $(DESTDIR)$(PREFIX)/lib/ray/
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@LIBS@|$(LDLIBS)|g' \
	    -e 's|@VERSION@|$(shell sed -n 's/^#define HD_VERSION "\(.*\)"/\1/p' include/heliodon/common.h)|g' \
	    heliodon.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/heliodon.pc

clean:
	rm -rf build build-asan

-include $(OBJ:.o=.d) $(BINS:%=%.d) $(UNITS:%=%.d)
