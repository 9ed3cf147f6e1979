# shlight -- see README.md.  Targets: all (libraries), test, demo, bench, install, lobes, clean.
CC       ?= cc
BUILD    ?= build
PREFIX   ?= /usr/local
DESTDIR  ?=
SANITIZE ?= 0

WARN     := -Wall -Wextra -Wpedantic -Werror
CSTD     := -std=c11 -D_XOPEN_SOURCE=700
OPT      ?= -O2
CFLAGS_ALL = $(CSTD) $(OPT) $(WARN) -fPIC -Iinclude -Isrc $(CFLAGS)
ifeq ($(SANITIZE),1)
  CFLAGS_ALL += -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -g
  LDFLAGS    += -fsanitize=address,undefined
endif
LDLIBS   += -lm -lpthread

LIB_SRC  := $(wildcard src/*.c)
LIB_OBJ  := $(LIB_SRC:%.c=$(BUILD)/%.o)
# The test build links a second copy of the objects with allocation hooks enabled.
TLIB_OBJ := $(LIB_SRC:%.c=$(BUILD)/thooks/%.o)
TEST_SRC := $(wildcard tests/*.c)
TEST_OBJ := $(TEST_SRC:%.c=$(BUILD)/%.o)
BENCH_SRC := $(wildcard bench/bench_*.c) bench/demo.c
BENCH_BIN := $(BENCH_SRC:bench/%.c=$(BUILD)/bench/%)
BENCH_COMMON := $(patsubst %.c,$(BUILD)/%.o,$(wildcard bench/common/*.c))

STATIC   := $(BUILD)/libshlight.a
SHARED   := $(BUILD)/libshlight.so

.PHONY: all test demo bench install lobes clean
all: $(STATIC) $(SHARED)

$(BUILD)/%.o: %.c $(wildcard include/*.h src/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -c $< -o $@

$(BUILD)/thooks/%.o: %.c $(wildcard include/*.h src/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -DSHL_ALLOC_HOOKS -c $< -o $@

$(STATIC): $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(SHARED): $(LIB_OBJ)
	$(CC) -shared $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(BUILD)/tests/run_tests: $(TEST_OBJ) $(TLIB_OBJ)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(BUILD)/tests/%.o: tests/%.c $(wildcard tests/*.h include/*.h src/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -Itests -c $< -o $@

test: $(BUILD)/tests/run_tests
	$(BUILD)/tests/run_tests $(TEST_FILTER)

$(BUILD)/bench/common/%.o: bench/common/%.c $(wildcard bench/common/*.h include/*.h src/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -Ibench/common -DSHL_BUILD_FLAGS="\"$(CSTD) $(OPT)\"" -c $< -o $@

$(BUILD)/bench/%: bench/%.c $(BENCH_COMMON) $(STATIC) $(wildcard bench/common/*.h)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS_ALL) -Ibench/common $(LDFLAGS) -o $@ $< $(BENCH_COMMON) $(STATIC) $(LDLIBS)

bench: $(BENCH_BIN)

demo: $(BUILD)/bench/demo
	$(BUILD)/bench/demo

# Regenerate the ZH lobe table (directions and weights) -- see tools/gen_lobes.c.
lobes: $(BUILD)/tools/gen_lobes
	$(BUILD)/tools/gen_lobes > src/zh_tables.c.new && mv src/zh_tables.c.new src/zh_tables.c

$(BUILD)/tools/gen_lobes: tools/gen_lobes.c src/sh_basis.c
	@mkdir -p $(dir $@)
	$(CC) $(CSTD) -O2 $(WARN) -Iinclude -Isrc -o $@ tools/gen_lobes.c src/sh_basis.c -lm

install: all
	install -d $(DESTDIR)$(PREFIX)/include $(DESTDIR)$(PREFIX)/lib/pkgconfig
	install -m 644 include/shlight.h $(DESTDIR)$(PREFIX)/include/
	install -m 644 $(STATIC) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(SHARED) $(DESTDIR)$(PREFIX)/lib/
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@VERSION@|0.1.0|g' tools/shlight.pc.in \
	  > $(DESTDIR)$(PREFIX)/lib/pkgconfig/shlight.pc

clean:
	rm -rf $(BUILD)
