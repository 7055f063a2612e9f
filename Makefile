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
# The version, in this one place: `dartspp --version` prints it with the commit of the checkout when the program
# was last linked (none outside a git checkout).
VERSION  := 0.48
COMMIT   := $(shell git rev-parse --short=12 HEAD 2>/dev/null)
VERSION_FLAGS = -DDARTSPP_VERSION='"$(VERSION)"' -DDARTSPP_COMMIT='"$(COMMIT)"'
LDLIBS   += -lembree3 -lOpenEXRCore-3_1 -lcjson -lpng -lstb -lflann -lm -fopenmp

DEB_PACKAGES = libembree-dev libopenexr-dev libflann-dev libcjson-dev libcmocka-dev libpng-dev libstb-dev pkg-config \
               libopenmpi-dev openmpi-bin chromium python3-dev python3-numpy python3-setuptools python3-pytest
DEPS_STAMP   = build/.deps-ok

LIB_SRC  = $(filter-out src/cli/main.c src/cluster/%,$(wildcard src/*/*.c))
MPI_SRC  = src/cluster/cluster_mpi.c
MPICC   ?= mpicc
CLI_SRC  = src/cli/main.c
# tests/<module>/test_*.c are the test programs, one binary each (build/san/tests/<module>/test_*), in a folder
# per module; the tests/*.c beside the folders are the fixtures they share, compiled once and linked into every
# test program (their headers are found by -Itests).
TEST_SRC = $(sort $(wildcard tests/*/test_*.c))
FIX_SRC  = $(wildcard tests/*.c)
# Header dependencies: every compile writes the headers it read into a .d file beside its output (-MMD -MP),
# which this Makefile includes at the end, so a header edit rebuilds exactly what includes it.
DEPFLAGS = -MMD -MP

# release build
OBJ      = $(LIB_SRC:src/%.c=build/obj/%.o)
# Every build runs JOBS compilers at once (default: one per core; JOBS=1 builds one file at a time), so that
# `make test` in a fresh clone builds in parallel.
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
MAKEFLAGS += -j$(JOBS)

# sanitizer build: the tests and a sanitized dartspp run under ASan + UBSan, at -O2 (the suite's renders 1.25×
# faster than at -O1: test_single_scatter_modes 69 s against 87 s, 2026-11-28)
SAN_FLAGS = -O2 -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
SAN_OBJ  = $(LIB_SRC:src/%.c=build/san/obj/%.o)
TEST_OBJ = $(TEST_SRC:tests/%.c=build/san/test-obj/%.o)
FIX_OBJ  = $(FIX_SRC:tests/%.c=build/san/test-obj/%.o)
TEST_BIN = $(TEST_SRC:tests/%.c=build/san/tests/%)

# The tiers are read from the test programs' own tag lines, not listed here. The quick tier (`make check`, for
# the edit-test loop) is every program with the line `/* tier: quick */`: the unit tests and one small
# consistency render per integrator against an independent reference. `make stress` runs every program with the
# line `/* tier: stress */` (those with a DARTSPP_STRESS=full matrix). `make test` runs every test program, the
# quick ones included. The programs, tiers and times: tests/README.md.
QUICK_SRC   = $(if $(TEST_SRC),$(shell grep -l '^/\* tier: quick \*/$$' $(TEST_SRC)))
STRESS_SRC  = $(if $(TEST_SRC),$(shell grep -l '^/\* tier: stress \*/$$' $(TEST_SRC)))
QUICK_TESTS = $(QUICK_SRC:tests/%.c=%)
# Programs that run with the machine to themselves (interrupt timings, peak memory): the line `/* run: alone */`.
ALONE_SRC   = $(if $(TEST_SRC),$(shell grep -l '^/\* run: alone \*/$$' $(TEST_SRC)))
ALONE_BIN   = $(ALONE_SRC:tests/%.c=build/san/tests/%)
QUICK_BIN   = $(QUICK_TESTS:%=build/san/tests/%)

.PHONY: all deps test check run clean stress reference bench-quick docs-keys python python-build
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

build/obj/%.o: src/%.c build/obj/%.d | $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(DEPFLAGS) $(LTO) -c $< -o $@
	@touch $@

# The archives are rebuilt from scratch whenever their object list changes (a source added or removed): `ar rcs`
# alone keeps the members of deleted sources, whose symbols then shadow their replacements (2026-11-28: a removed
# stub of src/derivative/time_kernel.c kept every pulse a box). build/<dir>/objects.txt holds the list.
build/%/objects.txt: FORCE
	@mkdir -p $(dir $@)
	@echo '$(LIB_SRC)' | cmp -s - $@ || echo '$(LIB_SRC)' > $@

.PHONY: FORCE
FORCE:

build/libdartspp.a: $(OBJ) build/obj/objects.txt
	rm -f $@
	$(if $(LTO),gcc-ar,$(AR)) rcs $@ $(OBJ)

build/dartspp: $(CLI_SRC) build/libdartspp.a
	$(CC) $(CFLAGS) $(VERSION_FLAGS) $(DEPFLAGS) $(LTO) $< build/libdartspp.a $(LDLIBS) -o $@

# dartspp-mpi: the same program with the render shared by MPI ranks (include/dartspp/cluster.h)
# (two sources in one command: -MMD would keep only the second one's headers, so -MM lists both first)
build/dartspp-mpi: $(CLI_SRC) $(MPI_SRC) build/libdartspp.a
	OMPI_CC=$(CC) $(MPICC) $(CFLAGS) -DDARTSPP_MPI -MM -MP -MT $@ $(CLI_SRC) $(MPI_SRC) > $@.d.tmp && mv $@.d.tmp $@.d
	OMPI_CC=$(CC) $(MPICC) $(CFLAGS) $(VERSION_FLAGS) $(LTO) -DDARTSPP_MPI $(CLI_SRC) $(MPI_SRC) build/libdartspp.a $(LDLIBS) -o $@

build/san/obj/%.o: src/%.c build/san/obj/%.d | $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(SAN_FLAGS) $(DEPFLAGS) -c $< -o $@
	@touch $@

build/san/libdartspp.a: $(SAN_OBJ) build/san/objects.txt
	rm -f $@
	$(AR) rcs $@ $(SAN_OBJ)

build/san/dartspp: $(CLI_SRC) build/san/libdartspp.a
	$(CC) $(CFLAGS) $(VERSION_FLAGS) $(SAN_FLAGS) $(DEPFLAGS) $< build/san/libdartspp.a $(LDLIBS) -o $@

# Test programs and fixtures are compiled to objects, then linked: a library edit relinks the programs.
build/san/test-obj/%.o: tests/%.c build/san/test-obj/%.d | $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(SAN_FLAGS) $(DEPFLAGS) -Itests -c $< -o $@
	@touch $@

build/san/tests/%: build/san/test-obj/%.o $(FIX_OBJ) build/san/libdartspp.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(SAN_FLAGS) $< $(FIX_OBJ) build/san/libdartspp.a $(LDLIBS) -lcmocka -o $@

.SECONDARY: $(TEST_OBJ) $(FIX_OBJ)

# The Python package (python/, docs/python.md): the library compiled once more as position-independent code
# (the release objects are not) into the extension module build/python/dartspp/_dartspp.so, beside the
# package's Python files. Debian's Python (PYTHON), whose python3-numpy the extension is compiled against.
# With the release build's LTO, and the library's symbols hidden so that its calls stay direct (PIC code calls
# through the PLT otherwise): a pass is then as fast as the CLI's; without both it took 7 % longer, with LTO
# alone 5 % (bench/python_overhead.py, 2026-11-26).
PYTHON  ?= /usr/bin/python3
PIC_FLAGS = -fPIC -fvisibility=hidden
PIC_OBJ  = $(LIB_SRC:src/%.c=build/pic/obj/%.o)
PY_SRC   = $(wildcard python/dartspp/*.py)
PY_BUILD = build/python/dartspp/_dartspp.so $(PY_SRC:python/%=build/python/%)

build/pic/obj/%.o: src/%.c build/pic/obj/%.d | $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(PIC_FLAGS) $(DEPFLAGS) $(LTO) -c $< -o $@
	@touch $@

build/pic/libdartspp.a: $(PIC_OBJ) build/pic/objects.txt
	rm -f $@
	$(if $(LTO),gcc-ar,$(AR)) rcs $@ $(PIC_OBJ)

build/python/dartspp/_dartspp.so: python/dartspp/_dartspp.c build/pic/libdartspp.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -fPIC -shared $(DEPFLAGS) $(LTO) -I$$($(PYTHON) -c 'import sysconfig; print(sysconfig.get_paths()["include"])') \
	  -I$$($(PYTHON) -c 'import numpy; print(numpy.get_include())') $< build/pic/libdartspp.a $(LDLIBS) -o $@

build/python/dartspp/%.py: python/dartspp/%.py
	@mkdir -p $(dir $@)
	cp $< $@

python-build: $(PY_BUILD)

# The README's install command: the package into Python's site folder (root: the first of
# site.getsitepackages(), /usr/local/lib/python3.X/dist-packages on Debian; others: their user site folder),
# or into PY_SITE when given.
python: python-build
	@site="$${PY_SITE:-$$($(PYTHON) -c 'import os, site; print(site.getsitepackages()[0] if os.geteuid() == 0 else site.getusersitepackages())')}"; \
	  mkdir -p "$$site/dartspp" && rm -rf "$$site/dartspp.tmp" && cp -r build/python/dartspp "$$site/dartspp.tmp" && \
	  rm -rf "$$site/dartspp" && mv "$$site/dartspp.tmp" "$$site/dartspp" && echo "installed dartspp for $(PYTHON) in $$site/dartspp"

# The README's test command. Unit, estimator and end-to-end tests, all under ASan + UBSan, and the Python
# package's tests (pytest, tests/python).
test: build/dartspp build/dartspp-mpi build/san/dartspp $(TEST_BIN) $(PY_BUILD)
	@PYTHON=$(PYTHON) DARTSPP_TEST_ALONE="$(ALONE_BIN)" tests/run_tests.sh $(TEST_BIN) tests/python

# The quick tier (QUICK_TESTS above, and the Python package's tests), with the same closing line as `make test`.
check: build/dartspp build/san/dartspp $(QUICK_BIN) $(PY_BUILD)
	@DARTSPP_QUICK=1 PYTHON=$(PYTHON) DARTSPP_TEST_ALONE="$(ALONE_BIN)" tests/run_tests.sh $(QUICK_BIN) tests/python

# The whole stress matrix (extreme media, anisotropy, gates, scales, geometry) and the long statistical cases
# that `make test` leaves out: every program tagged `/* tier: stress */` (tests/darts/test_darts.c,
# tests/darts/test_eda.c, tests/render/test_stress.c, tests/bsdf/test_materials.c, tests/render/test_fuzz_renders.c,
# ...) run with DARTSPP_STRESS=full, under ASan (what each adds and its time: tests/README.md). `make test` runs a
# fast subset of each. DARTSPP_STRESS_ONLY=text picks render cases by name.
STRESS_TESTS = $(STRESS_SRC:tests/%.c=build/san/tests/%)
stress: build/san/dartspp $(STRESS_TESTS)
	@DARTSPP_STRESS=full DARTSPP_TEST_ALONE="$(ALONE_BIN)" tests/run_tests.sh $(STRESS_TESTS)

# docs/keys.md between its markers is the output of `dartspp keys --markdown` (tests/scene/test_keys.c checks it).
docs-keys: build/dartspp
	@{ sed '/^<!-- begin: dartspp keys --markdown -->$$/q' docs/keys.md; ./build/dartspp keys --markdown; \
	   sed -n '/^<!-- end: dartspp keys --markdown -->$$/,$$p' docs/keys.md; } > docs/keys.md.tmp && mv docs/keys.md.tmp docs/keys.md

# The demo: fog-filled Cornell box, pulsed point light, a gate where multiple scattering dominates.
run: build/dartspp
	./build/dartspp render scenes/fogbox/fogbox.json --time 30 --output out/fogbox.exr

# A path-tracer reference: make reference SCENE=path.json [TIME=600] [OUT=refs/stem-pt.exr]
reference: build/dartspp
	bench/reference.sh $(SCENE) $(or $(TIME),600) $(or $(OUT),refs/$(basename $(notdir $(SCENE)))-pt.exr)

# A tour of the benchmarks on 2 cores (bench/quick.sh): reference, equal-time table, convergence plot, transient curve.
bench-quick: build/dartspp
	bench/quick.sh

clean:
	rm -rf build out

# An object whose .d file is missing (a build folder from before dependencies were tracked, or a deleted
# .d) is rebuilt: the .d files are prerequisites with an empty rule (GNU make manual, "Automatic
# Prerequisites"; the object is touched after the compile so that it stays newer than its .d).
DEP_FILES = $(OBJ:.o=.d) $(SAN_OBJ:.o=.d) $(PIC_OBJ:.o=.d) $(TEST_OBJ:.o=.d) $(FIX_OBJ:.o=.d)
$(DEP_FILES): ;
.PRECIOUS: $(DEP_FILES)
-include $(OBJ:.o=.d) $(SAN_OBJ:.o=.d) $(PIC_OBJ:.o=.d) $(TEST_OBJ:.o=.d) $(FIX_OBJ:.o=.d) build/dartspp.d \
         build/dartspp-mpi.d build/san/dartspp.d build/python/dartspp/_dartspp.d
