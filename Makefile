# dartspp — build, test, run. Every target that compiles depends on `deps`, which installs the Debian
# packages the build needs when they are missing, so each target works by itself on a fresh Debian 12.

CC       ?= cc
OPT      ?= -O3 -fno-math-errno
# Link-time optimisation of the release build (bench/pass_times.sh, 2026-11-25: -8 % per iteration of the
# fog Cornell box, images bit-identical); LTO= turns it off. The sanitizer build does not use it.
LTO      ?= -flto=auto
# ARCH=native (or a -march name) tunes the build for one CPU; the default build stays portable.
ARCH     ?=
CFLAGS   += -std=c11 -D_GNU_SOURCE $(OPT) $(if $(ARCH),-march=$(ARCH)) -g -Wall -Wextra -fopenmp -Iinclude \
            -I/usr/include/OpenEXR $(EXTRA_CFLAGS)
LDLIBS   += -lembree3 -lOpenEXRCore-3_1 -lcjson -lpng -lstb -lflann -lm -fopenmp

DEB_PACKAGES = libembree-dev libopenexr-dev libflann-dev libcjson-dev libcmocka-dev libpng-dev libstb-dev pkg-config \
               libopenmpi-dev openmpi-bin chromium
DEPS_STAMP   = build/.deps-ok

LIB_SRC  = $(filter-out src/cli/main.c src/cluster/%,$(wildcard src/*/*.c))
MPI_SRC  = src/cluster/cluster_mpi.c
MPICC   ?= mpicc
CLI_SRC  = src/cli/main.c
TEST_SRC = $(wildcard tests/test_*.c)

# release build
OBJ      = $(LIB_SRC:src/%.c=build/obj/%.o)
# sanitizer build: the tests and a sanitized dartspp run under ASan + UBSan
SAN_FLAGS = -O1 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
SAN_OBJ  = $(LIB_SRC:src/%.c=build/san/obj/%.o)
TEST_BIN = $(TEST_SRC:tests/%.c=build/san/tests/%)

.PHONY: all deps test run clean stress reference bench-quick
all: build/dartspp build/dartspp-mpi

deps: $(DEPS_STAMP)
$(DEPS_STAMP): Makefile
	@missing=""; for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "deps: installing$$missing"; \
	  if [ "$$(id -u)" != 0 ]; then echo "deps: need root to apt-get install$$missing" >&2; exit 1; fi; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing >/dev/null || exit 1; \
	fi
	@mkdir -p build && touch $@

build/obj/%.o: src/%.c $(wildcard include/dartspp/*.h src/*/*.h) | $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(LTO) -c $< -o $@

build/libdartspp.a: $(OBJ)
	$(if $(LTO),gcc-ar,$(AR)) rcs $@ $^

build/dartspp: $(CLI_SRC) build/libdartspp.a
	$(CC) $(CFLAGS) $(LTO) $< build/libdartspp.a $(LDLIBS) -o $@

# dartspp-mpi: the same program with the render shared by MPI ranks (include/dartspp/cluster.h)
build/dartspp-mpi: $(CLI_SRC) $(MPI_SRC) build/libdartspp.a
	OMPI_CC=$(CC) $(MPICC) $(CFLAGS) $(LTO) -DDARTSPP_MPI $(CLI_SRC) $(MPI_SRC) build/libdartspp.a $(LDLIBS) -o $@

build/san/obj/%.o: src/%.c $(wildcard include/dartspp/*.h src/*/*.h) | $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(SAN_FLAGS) -c $< -o $@

build/san/libdartspp.a: $(SAN_OBJ)
	$(AR) rcs $@ $^

build/san/dartspp: $(CLI_SRC) build/san/libdartspp.a
	$(CC) $(CFLAGS) $(SAN_FLAGS) $< build/san/libdartspp.a $(LDLIBS) -o $@

build/san/tests/%: tests/%.c tests/test_util.h build/san/libdartspp.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(SAN_FLAGS) $< build/san/libdartspp.a $(LDLIBS) -lcmocka -o $@

# The README's test command. Unit, estimator and end-to-end tests, all under ASan + UBSan.
test: build/dartspp build/dartspp-mpi build/san/dartspp $(TEST_BIN)
	@tests/run_tests.sh build/san/tests

# The whole stress matrix (extreme media, anisotropy, gates, scales, geometry): the estimator-level cases of
# tests/test_darts.c and tests/test_eda.c, the renders of tests/test_stress.c and all 18 material cases of
# tests/test_materials.c (how long: tests/README.md). `make test` runs a fast subset of each. DARTSPP_STRESS_ONLY=text picks render cases by name.
STRESS_TESTS = build/san/tests/test_darts build/san/tests/test_eda build/san/tests/test_stress build/san/tests/test_materials
stress: $(STRESS_TESTS)
	@rm -rf build/san/stress && mkdir -p build/san/stress && cp $(STRESS_TESTS) build/san/stress/
	@DARTSPP_STRESS=full tests/run_tests.sh build/san/stress

# The demo: fog-filled Cornell box, pulsed point light, a gate where multiple scattering dominates.
run: build/dartspp
	./build/dartspp render scenes/fogbox/fogbox.json --time 30 --output out/fogbox.exr

# A path-tracer reference: make reference SCENE=path.json [TIME=600] [OUT=refs/stem-pt.exr]
reference: build/dartspp
	bench/reference.sh $(SCENE) $(or $(TIME),600) $(or $(OUT),refs/$(basename $(notdir $(SCENE)))-pt.exr)

# Benchmarks in under 5 minutes on 2 cores: reference, equal-time table, convergence plot, transient curve.
bench-quick: build/dartspp
	bench/quick.sh

clean:
	rm -rf build out
