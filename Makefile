# shlight -- see README.md.  `make help` lists every target with its typical run time.
CC       ?= cc
# AVX512_EMULATE=1: the avx512 kernels compiled through SIMDe's AVX-512 emulation (Debian libsimde-dev)
# as AVX2 + FMA code and selected where avx2 runs (-DSHL_AVX512_EMULATE: simd/isa_list.h,
# simd/avx512/helper.h, src/dispatch.c), so they run on CPUs without AVX-512; its own default BUILD.
AVX512_EMULATE ?= 0
ifeq ($(AVX512_EMULATE),1)
  BUILD  ?= build/avx512-emu
  SHL_EMULATE_DEFS := -DSHL_AVX512_EMULATE
endif
BUILD    ?= build
PREFIX   ?= /usr/local
DESTDIR  ?=
SANITIZE ?= 0

WARN     := -Wall -Wextra -Wpedantic -Werror
CSTD     := -std=c11 -D_XOPEN_SOURCE=700
OPT      ?= -O2
CFLAGS_ALL = $(CSTD) $(OPT) $(WARN) -fPIC -Iinclude -Isrc $(SHL_EMULATE_DEFS) $(CFLAGS)
# SANITIZE=1: AddressSanitizer + UBSan; SANITIZE=thread: ThreadSanitizer.
ifeq ($(SANITIZE),1)
  CFLAGS_ALL += -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -g
  LDFLAGS    += -fsanitize=address,undefined
endif
ifeq ($(SANITIZE),thread)
  CFLAGS_ALL += -fsanitize=thread -g
  LDFLAGS    += -fsanitize=thread
endif
LDLIBS   += -lm -lpthread

# SIMD batch kernels (simd/): the ISAs are the lines of simd/isa_list.h that $(CC)'s target keeps
# (read with its preprocessor, so the C code and the build see the same list), each with its flags.
# Every kernel text simd/<kernel>_batch.h is compiled once per ISA into $(BUILD)/simd/<isa>/<kernel>_batch.o,
# with simd/<isa>/helper.h included first and only that ISA's flags (e.g. -mavx2 -mfma);
# src/dispatch.c picks a table at run time.
SHL_ISAS    := $(shell $(CC) -E -P -x c $(SHL_EMULATE_DEFS) '-DSHL_ISA(name,flags,cpu)=name' simd/isa_list.h)
SHL_KERNELS := $(patsubst simd/%.h,%,$(wildcard simd/*_batch.h))
ifeq ($(filter scalar,$(SHL_ISAS)),)
  $(error Makefile: '$(CC) -E simd/isa_list.h' lists no scalar ISA (got '$(SHL_ISAS)'))
endif
# $(call isa_flags,ISA): the flags column of ISA's line, without its quotes.
isa_flags = $(shell $(CC) -E -P -x c $(SHL_EMULATE_DEFS) '-DSHL_ISA(name,flags,cpu)=name flags' simd/isa_list.h | sed -n 's/^$(1) "\(.*\)"$$/\1/p')
SIMD_OBJ := $(foreach i,$(SHL_ISAS),$(SHL_KERNELS:%=simd/$(i)/%.o))

LIB_SRC  := $(wildcard src/*.c)
LIB_OBJ  := $(LIB_SRC:%.c=$(BUILD)/%.o) $(SIMD_OBJ:%=$(BUILD)/%)
# The test build links a second copy of the objects with allocation hooks enabled.
TLIB_OBJ := $(LIB_SRC:%.c=$(BUILD)/thooks/%.o) $(SIMD_OBJ:%=$(BUILD)/thooks/%)
TEST_SRC := $(wildcard tests/*.c)
TEST_OBJ := $(TEST_SRC:%.c=$(BUILD)/%.o)
BENCH_SRC := $(wildcard bench/bench_*.c) bench/demo.c
BENCH_BIN := $(BENCH_SRC:bench/%.c=$(BUILD)/bench/%)
BENCH_COMMON := $(patsubst %.c,$(BUILD)/%.o,$(wildcard bench/common/*.c))

# The version is written once, as SHL_VERSION_STRING in include/shlight.h.  The shared library is
# libshlight.so.X.Y.Z with SONAME libshlight.so.X (X = major) and the symlinks libshlight.so.X and
# libshlight.so (the link-time name), in $(BUILD) and on install.
SHL_VERSION := $(shell sed -n 's/^\#define SHL_VERSION_STRING "\([0-9.]*\)"$$/\1/p' include/shlight.h)
SHL_SOMAJOR := $(firstword $(subst ., ,$(SHL_VERSION)))
SONAME      := libshlight.so.$(SHL_SOMAJOR)
ifeq ($(SHL_SOMAJOR),)
  $(error Makefile: no SHL_VERSION_STRING "X.Y.Z" found in include/shlight.h)
endif
STATIC   := $(BUILD)/libshlight.a
SHARED   := $(BUILD)/libshlight.so
SHARED_REAL := $(BUILD)/libshlight.so.$(SHL_VERSION)

.PHONY: all test test-valgrind test-neon test-avx512-emu demo bench install lobes clean
all: $(STATIC) $(SHARED)

# Every object depends on every header (simple and safe for a tree this size).
HDRS     := $(wildcard include/*.h src/*.h simd/*.h simd/*/*.h)

$(BUILD)/%.o: %.c $(HDRS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/thooks/%.o: %.c $(HDRS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -DSHL_ALLOC_HOOKS -c $< -o $@

# $(call isa_rules,ISA,OUT,EXTRA): the kernels of ISA into OUT/simd/ISA/, compiled with EXTRA.
define isa_rules
$(2)/simd/$(1)/%.o: simd/%.h $$(HDRS)
	@mkdir -p $$(dir $$@)
	$$(CC) $$(CFLAGS_ALL) $(3) $$(SHL_ISA_FLAGS_$(1)) -include simd/$(1)/helper.h -x c -c $$< -o $$@
endef
$(foreach i,$(SHL_ISAS),$(eval SHL_ISA_FLAGS_$(i) := $(call isa_flags,$(i))) \
  $(eval $(call isa_rules,$(i),$(BUILD),)) $(eval $(call isa_rules,$(i),$(BUILD)/thooks,-DSHL_ALLOC_HOOKS)))

$(BUILD)/src/dispatch.o $(BUILD)/thooks/src/dispatch.o: CFLAGS_ALL += \
  -DSHL_BUILD_CFLAGS="\"$(strip $(CSTD) $(OPT) $(CFLAGS) $(if $(filter-out 0,$(SANITIZE)),SANITIZE=$(SANITIZE)) $(SHL_EMULATE_DEFS))\""

$(STATIC): $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

# Public symbols only: the library objects are compiled with -fvisibility=hidden and shlight.h
# makes its own declarations default-visible, so the .so exports exactly the shl_[a-z]* API
# (tools/check_symbols.sh).  Hidden symbols stay global in the objects: programs linked with
# libshlight.a or the objects (tests, bench, tools) still resolve the internal shl__* ones.
$(LIB_OBJ) $(TLIB_OBJ): CFLAGS_ALL += -fvisibility=hidden

$(SHARED_REAL): $(LIB_OBJ)
	$(CC) -shared -Wl,-soname,$(SONAME) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(BUILD)/$(SONAME): $(SHARED_REAL)
	ln -sf $(notdir $<) $@

$(SHARED): $(BUILD)/$(SONAME)
	ln -sf $(SONAME) $@

# The boundary: the .so exports only shlight.h's shl_[a-z]* functions and has its SONAME;
# bench/ and tests/ reach shl__ internals only through the allowed internal headers
# (tools/check_symbols.sh lists them) and never through the .so.
.PHONY: check-symbols
check-symbols: $(SHARED)
	bash tools/check_symbols.sh $(BUILD)

$(BUILD)/tests/run_tests: $(TEST_OBJ) $(TLIB_OBJ)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(BUILD)/tests/%.o: tests/%.c $(wildcard tests/*.h) $(HDRS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -Itests -c $< -o $@

# The benchmark harness (bench/common) is built once, into the static archive $(BENCH_LIB), which
# the bench programs and the test runner link (tests/test_render.c renders a tiny scene with it).
# Its parallel loop is the library's (src/parallel.h): it links the library statically, with
# libshlight.a or the test build's objects.
BENCH_LIB := $(BUILD)/libshlbench.a
$(BENCH_LIB): $(BENCH_COMMON)
	@rm -f $@
	ar rcs $@ $^
$(BUILD)/tests/run_tests: $(BENCH_LIB)
$(BUILD)/tests/test_render.o: CFLAGS_ALL += -Ibench/common
$(BUILD)/tests/test_render.o: $(wildcard bench/common/*.h)

# A full run also writes its lines to $(BUILD)/test.log (read by check-readme-figures).
test: $(BUILD)/tests/run_tests
	$(BUILD)/tests/run_tests $(TEST_FILTER) $(if $(TEST_FILTER),,--log $(BUILD)/test.log)

# README's measured figures against what the last full `make test` printed.
.PHONY: check-readme-figures
check-readme-figures:
	@test -f $(BUILD)/test.log || $(MAKE) test
	python3 tools/check_readme_figures.py $(BUILD)/test.log README.md

# The whole suite on AArch64 (scalar and NEON kernels): cross-compiled with
# Debian's gcc-aarch64-linux-gnu, run under qemu-user emulation.
NEON_CC   ?= aarch64-linux-gnu-gcc
NEON_QEMU ?= $(shell command -v qemu-aarch64-static || command -v qemu-aarch64)
test-neon:
	$(MAKE) CC=$(NEON_CC) BUILD=$(BUILD)/aarch64 SANITIZE=0 $(BUILD)/aarch64/tests/run_tests
	$(NEON_QEMU) -L /usr/aarch64-linux-gnu $(BUILD)/aarch64/tests/run_tests $(TEST_FILTER)

# The whole suite with the avx512 kernels run through SIMDe's AVX-512 emulation on an AVX2 + FMA
# CPU (AVX512_EMULATE=1, in $(BUILD)/avx512-emu; needs libsimde-dev): the default choice is avx512
# there (tests/test_simd.c: simd_isa_matches_cpu), SHLIGHT_ISA=avx512 selects it for every test.
test-avx512-emu:
	$(MAKE) AVX512_EMULATE=1 BUILD=$(BUILD)/avx512-emu $(BUILD)/avx512-emu/tests/run_tests
	SHLIGHT_ISA=avx512 $(BUILD)/avx512-emu/tests/run_tests $(TEST_FILTER)

# The whole suite under valgrind memcheck (any invalid access or leak fails; about
# 13 minutes on the CI machine), except the tests whose references need long double
# precision, which valgrind computes in double: sphere_grad_vs_fd (8th-order finite
# differences of tests/capref.c at a gap of 1e-7 radii).  They run natively and
# under ASan/UBSan.  Test-name filters: tests/harness.c.
VALGRIND_TESTS ?= -sphere_grad_vs_fd
test-valgrind: $(BUILD)/tests/run_tests
	valgrind -q --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=definite,indirect \
	  $(BUILD)/tests/run_tests $(VALGRIND_TESTS)

$(BUILD)/bench/common/%.o: bench/common/%.c $(wildcard bench/common/*.h include/*.h src/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -Ibench/common -DSHL_BUILD_FLAGS="\"$(CSTD) $(OPT)\"" -c $< -o $@

$(BUILD)/bench/%: bench/%.c $(BENCH_LIB) $(STATIC) $(wildcard bench/common/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -Ibench/common $(LDFLAGS) -o $@ $< $(BENCH_LIB) $(STATIC) $(LDLIBS)

bench: $(BENCH_BIN)

demo: $(BUILD)/bench/demo
	$(BUILD)/bench/demo

# bench-vs-commit OLD=<rev>: shl_polygon (triangle, lmax 2, 4, 8, 14, 30; bench/polygon_call.c, public
# API only) of commit <rev> against this tree, same CC and OPT, back to back: <rev>'s tree from
# `git archive` into $(BUILD)/old-<hash>/src, its libshlight.a built there by its own Makefile (kept
# for the next run), the same bench source linked against each library; bench/vs_commit.sh alternates
# the two binaries for BVC_ROUNDS (7) rounds and prints medians and old / new ratios.  The issue-16
# baseline is OLD=090cb1d (last commit before the issue-16 work; its polygon code equals 2952b88's).
BVC_ROUNDS ?= 7
BVC_CFLAGS  = $(CSTD) $(OPT) $(WARN)
.PHONY: bench-vs-commit
$(BUILD)/bench/polygon_call: bench/polygon_call.c $(STATIC) include/shlight.h
	@mkdir -p $(dir $@)
	$(CC) $(BVC_CFLAGS) -Iinclude -o $@ $< $(STATIC) $(LDLIBS)
bench-vs-commit: $(BUILD)/bench/polygon_call
	@test -n "$(OLD)" || { echo "bench-vs-commit: name the old commit, e.g. OLD=090cb1d" >&2; exit 1; }
	@set -e; rev=$$(git rev-parse --short=7 "$(OLD)^{commit}"); dir=$(BUILD)/old-$$rev; \
	if [ ! -f $$dir/src/build/libshlight.a ]; then \
	  rm -rf $$dir; mkdir -p $$dir/src; git archive $$rev | tar -x -C $$dir/src; \
	  $(MAKE) --no-print-directory -C $$dir/src BUILD=build CC="$(CC)" OPT="$(OPT)" build/libshlight.a >/dev/null; fi; \
	$(CC) $(BVC_CFLAGS) -I$$dir/src/include -o $$dir/polygon_call bench/polygon_call.c $$dir/src/build/libshlight.a $(LDLIBS); \
	echo "old = $$rev ($$dir/polygon_call), new = this tree ($(BUILD)/bench/polygon_call), $(CC) $(OPT)"; \
	sh bench/vs_commit.sh $$dir/polygon_call $(BUILD)/bench/polygon_call $(BVC_ROUNDS)

# The papers' results tables with the PRT harness (about 4 minutes on 2 idle cores; needs the
# test meshes: SHLIGHT_MESHES=DIR, default ../shared/meshes; build/bench/bench_tables --help).
# Writes $(BUILD)/bench-tables/ (RESULTS-tables.md, tables/*.csv, manifest.txt), never the tracked
# files; BENCH_TABLES_SECTIONS="annen hvl" runs a subset (not accepted).  bench-tables-accept
# copies a complete run (manifest: "complete: yes") over bench/RESULTS-tables.md and bench/tables/,
# and the plots that `make plots` drew from it over bench/plots/.  HVL Table 2's path-traced
# reference runs tools/hvl_reference.py in the oracle venv ($(VENV)) when it exists (~15 s, then
# cached in $(BUILD)/bench-tables/hvl2022_table2/cache); without it that table says so.
BENCH_TABLES_DIR := $(BUILD)/bench-tables
.PHONY: bench-tables bench-tables-accept
bench-tables: $(BUILD)/bench/bench_tables
	@rm -f $(BENCH_TABLES_DIR)/plots/*.png $(BENCH_TABLES_DIR)/plots/*.svg
	SHLIGHT_ORACLE_PYTHON=$(if $(wildcard $(VENV)/bin/python),$(abspath $(VENV)/bin/python)) \
	  $(BUILD)/bench/bench_tables -o $(BENCH_TABLES_DIR) $(if $(SHLIGHT_MESHES),--meshes $(SHLIGHT_MESHES)) $(BENCH_TABLES_SECTIONS)

bench-tables-accept:
	@grep -qx 'complete: yes' $(BENCH_TABLES_DIR)/manifest.txt 2>/dev/null || { \
	  echo "bench-tables-accept: $(BENCH_TABLES_DIR)/manifest.txt does not record a complete run" \
	       "(run 'make bench-tables' with all sections and every scene); nothing copied" >&2; exit 1; }
	rm -f bench/tables/*.csv
	cp $(BENCH_TABLES_DIR)/tables/*.csv $(BENCH_TABLES_DIR)/manifest.txt bench/tables/
	sed 's|$(BENCH_TABLES_DIR)/tables/|bench/tables/|g' $(BENCH_TABLES_DIR)/RESULTS-tables.md > bench/RESULTS-tables.md
	@if ls $(BENCH_TABLES_DIR)/plots/*.png >/dev/null 2>&1; then \
	  cp $(BENCH_TABLES_DIR)/plots/*.png $(BENCH_TABLES_DIR)/plots/*.svg bench/plots/ && echo "accepted, with the plots of 'make plots'"; \
	else echo "accepted; the plots were not drawn: run 'make plots' and accept again"; fi

# Every CSV under bench/tables parses with a constant field count (tools/check_csv.py).
.PHONY: check-csv
check-csv:
	python3 tools/check_csv.py bench/tables

# Regenerate the ZH lobe table (directions and weights) -- see tools/gen_lobes.c.
lobes: $(BUILD)/tools/gen_lobes
	$(BUILD)/tools/gen_lobes > src/zh_tables.c.new && mv src/zh_tables.c.new src/zh_tables.c

$(BUILD)/tools/gen_lobes: tools/gen_lobes.c $(STATIC)
	@mkdir -p $(dir $@)
	$(CC) $(CSTD) -O2 $(WARN) -Iinclude -Isrc -o $@ tools/gen_lobes.c $(STATIC) $(LDLIBS)

# Regenerate the real-SH recurrence tables -- see tools/gen_sh_tables.c.
.PHONY: sh-tables
sh-tables: $(BUILD)/tools/gen_sh_tables
	$(BUILD)/tools/gen_sh_tables > src/sh_tables.c.new && mv src/sh_tables.c.new src/sh_tables.c

$(BUILD)/tools/gen_sh_tables: tools/gen_sh_tables.c include/shlight.h
	@mkdir -p $(dir $@)
	$(CC) $(CSTD) -O2 $(WARN) -Iinclude -o $@ tools/gen_sh_tables.c -lm

install: all
	install -d $(DESTDIR)$(PREFIX)/include $(DESTDIR)$(PREFIX)/lib/pkgconfig
	install -m 644 include/shlight.h $(DESTDIR)$(PREFIX)/include/
	install -m 644 $(STATIC) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(SHARED_REAL) $(DESTDIR)$(PREFIX)/lib/
	ln -sf $(notdir $(SHARED_REAL)) $(DESTDIR)$(PREFIX)/lib/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(PREFIX)/lib/libshlight.so
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@VERSION@|$(SHL_VERSION)|g' tools/shlight.pc.in \
	  > $(DESTDIR)$(PREFIX)/lib/pkgconfig/shlight.pc

# Removes exactly the four files and two symlinks install wrote (same PREFIX and DESTDIR);
# directories stay.
.PHONY: uninstall
uninstall:
	rm -f $(DESTDIR)$(PREFIX)/include/shlight.h $(DESTDIR)$(PREFIX)/lib/libshlight.a \
	  $(DESTDIR)$(PREFIX)/lib/$(notdir $(SHARED_REAL)) $(DESTDIR)$(PREFIX)/lib/$(SONAME) \
	  $(DESTDIR)$(PREFIX)/lib/libshlight.so $(DESTDIR)$(PREFIX)/lib/pkgconfig/shlight.pc

clean:
	rm -rf $(BUILD)

# ---- robustness: libFuzzer targets (tests/fuzz/) and the stress run (tests/stress/) ----
# make fuzz [FUZZ_SECONDS=60 | FUZZ_RUNS=N [FUZZ_SEED=1]] [FUZZ_TARGETS="fuzz_polygon ..."] [FUZZ_FLAGS=...]:
# builds every tests/fuzz/fuzz_*.c with clang and -fsanitize=fuzzer,address,undefined,
# linked with the library objects built with the same sanitizers and the allocation
# hooks (in $(BUILD)/fuzz), then runs each target for FUZZ_SECONDS seconds from its
# committed seed corpus tests/fuzz/corpus/<target>/; with FUZZ_RUNS, N inputs per target
# from the fixed seed FUZZ_SEED instead, deterministic (what CI runs): from an empty
# $(BUILD)/fuzz/corpus/<target>/, with -use_cmp=0 (the compare dictionary picked up heap
# addresses) and -reload=0 (the once-a-second re-read of the output corpus ran an extra
# input at a time-dependent point), and the fuzz build runs the thread pool's rounds serially
# (SHL_SERIAL_POOL, src/parallel.c); before these, two runs of seed 1 found different
# inputs (tests/fuzz/README.md).  New inputs go to $(BUILD)/fuzz/corpus/<target>/,
# failing inputs to $(BUILD)/fuzz/artifacts/, the full log to $(BUILD)/fuzz/<target>.log.
# Every target runs even if an earlier one fails; make fails if any did.
FUZZ_SECONDS ?= 60
FUZZ_CC      ?= clang
FUZZ_FLAGS   ?=
FUZZ_RUNS    ?=
FUZZ_SEED    ?= 1
FUZZ_LIMIT   := $(if $(FUZZ_RUNS),-runs=$(FUZZ_RUNS) -seed=$(FUZZ_SEED) -use_cmp=0 -reload=0,-max_total_time=$(FUZZ_SECONDS))
FUZZ_TARGETS ?= $(patsubst tests/fuzz/%.c,%,$(wildcard tests/fuzz/fuzz_*.c))
FUZZ_DIR     := $(BUILD)/fuzz
ifeq ($(SANITIZE),fuzzer)
  CFLAGS_ALL += -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all \
                -fno-omit-frame-pointer -g -DSHL_ALLOC_HOOKS -DSHL_SERIAL_POOL
endif
.PHONY: fuzz fuzz-build fuzz-bins fuzz-repro stress
fuzz: fuzz-build
	@fail=""; for t in $(FUZZ_TARGETS); do \
	  $(if $(FUZZ_RUNS),rm -rf $(FUZZ_DIR)/corpus/$$t;) mkdir -p $(FUZZ_DIR)/corpus/$$t $(FUZZ_DIR)/artifacts; \
	  echo "== $$t: $(FUZZ_LIMIT) from tests/fuzz/corpus/$$t"; \
	  $(FUZZ_DIR)/tests/fuzz/$$t $(FUZZ_LIMIT) -timeout=60 -print_final_stats=1 \
	    -artifact_prefix=$(FUZZ_DIR)/artifacts/$$t- $(FUZZ_FLAGS) \
	    $(FUZZ_DIR)/corpus/$$t tests/fuzz/corpus/$$t > $(FUZZ_DIR)/$$t.log 2>&1; rc=$$?; \
	  grep -v -e '^#[0-9]*[[:space:]]*\(NEW\|REDUCE\|pulse\)' -e '^INFO: ' $(FUZZ_DIR)/$$t.log | tail -n 40; \
	  grep -e ' cov: ' $(FUZZ_DIR)/$$t.log | tail -n 1; \
	  [ $$rc -eq 0 ] || fail="$$fail $$t"; \
	done; \
	if [ -n "$$fail" ]; then \
	  for t in $$fail; do \
	    echo "== $$t failed: what it reported, and its failing inputs (base64; replay: base64 -d > f; $(FUZZ_DIR)/tests/fuzz/$$t f)"; \
	    grep -m 3 -e 'property violated' -e 'runtime error' -e 'ERROR: ' -e 'SUMMARY: ' $(FUZZ_DIR)/$$t.log; \
	    for a in $(FUZZ_DIR)/artifacts/$$t-*; do [ -f "$$a" ] && { echo "$$a:"; base64 -w 0 "$$a" | head -c 4096; echo; }; done; \
	  done; \
	  echo "fuzz: FAILED:$$fail on $$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //'), avx512f: $$(grep -c -m1 avx512f /proc/cpuinfo) (inputs in $(FUZZ_DIR)/artifacts/)"; \
	  exit 1; \
	fi; \
	echo "fuzz: all targets passed"

# The fuzz binaries, built in a sub-make with clang and SANITIZE=fuzzer.
fuzz-build:
	$(MAKE) CC=$(FUZZ_CC) BUILD=$(FUZZ_DIR) SANITIZE=fuzzer FUZZ_TARGETS="$(FUZZ_TARGETS)" fuzz-bins

fuzz-bins: $(FUZZ_TARGETS:%=$(BUILD)/tests/fuzz/%)

$(BUILD)/tests/fuzz/%: tests/fuzz/%.c tests/fuzz/fuzz_common.h $(wildcard tests/*.h) $(LIB_OBJ)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -fsanitize=fuzzer -Itests -o $@ $< $(LIB_OBJ) $(LDLIBS)

# Replay the saved reproducers of open library bugs, tests/fuzz/crashes/<target>-*
# (not in CI: each prints its violation until the bug is fixed; once fixed, the
# input moves to the seed corpus tests/fuzz/corpus/<target>/).
fuzz-repro: fuzz-build
	@for f in tests/fuzz/crashes/fuzz_*; do \
	  [ -f "$$f" ] || continue; t=$$(basename $$f | sed 's/-.*//'); \
	  echo "== $$f"; $(FUZZ_DIR)/tests/fuzz/$$t $$f 2>&1 | grep -e 'property violated' -e 'runtime error' | head -2; \
	done

# make stress [STRESS_N=10000000] [STRESS_THREADS=2]: random and near-degenerate polygons
# and spheres over lmax 0..30 in double and float (tests/stress/stress.c); prints the count of
# non-finite outputs and the worst errors against the quadrature references.
STRESS_N       ?= 10000000
STRESS_THREADS ?= 2
stress: $(BUILD)/tests/stress/stress
	$(BUILD)/tests/stress/stress $(STRESS_N) $(STRESS_THREADS)

$(BUILD)/tests/stress/stress: tests/stress/stress.c tests/ref_quad.c tests/capref.c $(STATIC) $(wildcard tests/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -Itests $(LDFLAGS) -o $@ tests/stress/stress.c tests/ref_quad.c tests/capref.c $(STATIC) $(LDLIBS)

# ---- Python tools: Mitsuba 3 / Dr.Jit accuracy oracle (tools/oracle.py, bench/ORACLE.md), plots ----
# venv: build/venv from tools/requirements.txt (Mitsuba, Dr.Jit, numpy, pillow); venv-plot:
# build/venv-plot from tools/requirements-plot.txt (numpy, matplotlib).  Each is reinstalled
# only when its requirements file changes (its sha256 is kept in a stamp file).
# oracle: full run, writes bench/ORACLE.md.  oracle-check: the CI subset (20 configurations,
# one 64x64 image); non-zero exit on any disagreement.  Both run the harness export tool
# (bench/oracle_export.c) for the image check.  Dr.Jit's LLVM backend loads a system libLLVM at
# run time: oracle-llvm (tools/find_libllvm.py, Python stdlib only) finds one that Dr.Jit 1.5 can
# use, or stops at once with the command that installs one, before the venv and the build;
# tools/oracle.py then sets DRJIT_LIBLLVM_PATH to it.  plots: tools/plot.py on the latest
# bench-tables run ($(BUILD)/bench-tables/plots; bench-tables-accept copies them to bench/plots/).
VENV       ?= build/venv
VENV_PLOT  ?= build/venv-plot
PYTHON     ?= python3
# $(call venv_install,DIR,REQUIREMENTS)
define venv_install
@h=$$(sha256sum $(2) | cut -d' ' -f1); \
if [ -x $(1)/bin/python ] && [ "$$(cat $(1)/.requirements.sha256 2>/dev/null)" = "$$h" ]; then \
  echo "venv: $(1) up to date"; \
else \
  echo "venv: installing $(2) into $(1)"; \
  rm -rf $(1) && $(PYTHON) -m venv $(1) && \
  $(1)/bin/pip install -q --disable-pip-version-check -r $(2) && \
  echo "$$h" > $(1)/.requirements.sha256; \
fi
endef
ORACLE_ENV := SHLIGHT_LIB=$(abspath $(SHARED)) SHLIGHT_EXPORT=$(abspath $(BUILD)/bench/oracle_export)
.PHONY: venv venv-plot oracle-llvm oracle oracle-check plots
venv:
	$(call venv_install,$(VENV),tools/requirements.txt)

venv-plot:
	$(call venv_install,$(VENV_PLOT),tools/requirements-plot.txt)

oracle-llvm:
	@p=$$($(PYTHON) tools/find_libllvm.py) && echo "oracle: Dr.Jit's LLVM backend will use $$p"

# The venv and the binaries in a sub-make, so that nothing starts before oracle-llvm passed.
oracle: oracle-llvm
	@$(MAKE) --no-print-directory venv $(SHARED) $(BUILD)/bench/oracle_export
	$(ORACLE_ENV) $(VENV)/bin/python tools/oracle.py

oracle-check: oracle-llvm
	@$(MAKE) --no-print-directory venv $(SHARED) $(BUILD)/bench/oracle_export
	$(ORACLE_ENV) $(VENV)/bin/python tools/oracle.py --check

plots: venv-plot
	$(VENV_PLOT)/bin/python tools/plot.py --tables $(BENCH_TABLES_DIR)/tables --out $(BENCH_TABLES_DIR)/plots

# ---- make help: every target, one line each, with its typical time on the 2-core CI machine
# (make -j2 from a clean tree; a build step already done is not paid again).
.PHONY: help
help:
	@echo 'shlight targets (typical time on 2 cores, make -j2; details in README.md):'
	@printf '  %-19s %-64s %s\n' all 'build/libshlight.a and build/libshlight.so (the default target)' '~15 s'
	@printf '  %-19s %-64s %s\n' test 'build and run every test (TEST_FILTER=a,b,-c selects by name)' '1-3 min'
	@printf '  %-19s %-64s %s\n' test-valgrind 'the suite under valgrind memcheck (CI)' '13 min'
	@printf '  %-19s %-64s %s\n' test-neon 'the suite built for AArch64, run under qemu-user (CI)' '~20 min'
	@printf '  %-19s %-64s %s\n' test-avx512-emu 'the suite with the avx512 kernels emulated by SIMDe on AVX2 (CI)' '~1 min build + 30 s'
	@printf '  %-19s %-64s %s\n' demo 'render build/demo.png; stage times and grid-vs-analytic error' '~20 s build + 5 s (12 s 1st run)'
	@printf '  %-19s %-64s %s\n' bench 'build the benchmarks into $$(BUILD)/bench/ (runs none)' '~20 s'
	@printf '  %-19s %-64s %s\n' bench-vs-commit 'OLD=<rev>: shl_polygon of <rev> vs this tree, 7 alternated rounds' '~30 s build + 1 min'
	@printf '  %-19s %-64s %s\n' bench-tables 'the papers'\'' tables into build/bench-tables/ (needs the meshes)' '~5 min'
	@printf '  %-19s %-64s %s\n' bench-tables-accept 'copy a complete bench-tables run (+ plots) over bench/' '<1 s'
	@printf '  %-19s %-64s %s\n' install 'all + header, .a, .so + 2 symlinks, .pc into $$(DESTDIR)$$(PREFIX)' 'build + <1 s'
	@printf '  %-19s %-64s %s\n' uninstall 'remove exactly those 6 entries (same PREFIX and DESTDIR)' '<1 s'
	@printf '  %-19s %-64s %s\n' lobes 'regenerate src/zh_tables.c with tools/gen_lobes' '1-2.5 min'
	@printf '  %-19s %-64s %s\n' sh-tables 'regenerate src/sh_tables.c with tools/gen_sh_tables' '1 s'
	@printf '  %-19s %-64s %s\n' clean 'remove $$(BUILD)' '<1 s'
	@printf '  %-19s %-64s %s\n' fuzz 'libFuzzer targets x FUZZ_SECONDS (60) each, ASan + UBSan' '~1 min build + 8 min'
	@printf '  %-19s %-64s %s\n' fuzz-build 'build the fuzz binaries with clang into $$(BUILD)/fuzz/' '~1 min'
	@printf '  %-19s %-64s %s\n' fuzz-bins '(inside fuzz-build) the fuzz binaries for the current CC' '~1 min'
	@printf '  %-19s %-64s %s\n' fuzz-repro 'replay the open-bug reproducers tests/fuzz/crashes/*' 'fuzz-build + seconds'
	@printf '  %-19s %-64s %s\n' stress 'STRESS_N (1e7) random and near-degenerate cases, 2 threads' '~7 min'
	@printf '  %-19s %-64s %s\n' venv 'build/venv from tools/requirements.txt (Mitsuba, Dr.Jit)' 'minutes (download); then <1 s'
	@printf '  %-19s %-64s %s\n' venv-plot 'build/venv-plot: numpy + matplotlib (tools/requirements-plot.txt)' '~1-3 min (download); then <1 s'
	@printf '  %-19s %-64s %s\n' plots 'draw the latest bench-tables run into build/bench-tables/plots' '~1 min'
	@printf '  %-19s %-64s %s\n' oracle-llvm 'find a libLLVM >= 17 for Dr.Jit, or say which package to install' '<1 s'
	@printf '  %-19s %-64s %s\n' oracle 'full Mitsuba 3 / Dr.Jit comparison, writes bench/ORACLE.md' '39 min'
	@printf '  %-19s %-64s %s\n' oracle-check 'the CI subset of the oracle (20 configurations, one image)' '4 min'
	@printf '  %-19s %-64s %s\n' check-symbols 'the .so exports only shl_[a-z]*, has its SONAME; internal boundary' '<1 s + build'
	@printf '  %-19s %-64s %s\n' check-readme-figures "README's test figures equal what the last full make test printed" '<1 s'
	@printf '  %-19s %-64s %s\n' check-csv 'every CSV under bench/tables/ parses with a constant field count' '<1 s'
	@printf '  %-19s %-64s %s\n' help 'this list' 'instant'
	@echo 'Variables: CC, BUILD (build/), OPT, SANITIZE=1|thread, AVX512_EMULATE=1, PREFIX (/usr/local), DESTDIR,'
	@echo '  TEST_FILTER, FUZZ_SECONDS, FUZZ_TARGETS, STRESS_N, STRESS_THREADS.'
