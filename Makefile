# drape: GNU-style Makefile.  See README.md.
#
#   make deps      install the Debian packages drape needs (apt-get, only
#                  when one is missing)
#   make / all     build ./drape
#   make run       run the default scene (scenes/cusick.yaml)
#   make check     build and run the Check test suite
#   make unit      the Check suite without rebuilding ./drape
#   make check-slurm  test scripts/slurm/ on a real single-node Slurm (root;
#                  installs slurm-wlm and munge; docs/batch.md)
#   make bench-quick  integrators on the default scenes -> docs/integrators.md
#   make bench     work-precision report -> docs/performance/ (drape bench;
#                  installs gnuplot-nox when missing; docs/performance.md)
#   make bench-ensemble  the drape test, accurate against fast ensembles
#                  -> docs/performance.md (1-2 h of CPU)
#   make bench-convergence  the drape test against the lattice spacing on
#                  three fabrics -> docs/convergence.md (hours of CPU,
#                  resumable)
#   make bench-anisotropy  the lattice's preference for diagonal folds:
#                  in the bending energy of a smooth skirt, and in a rest
#                  state turned by 45 degrees (docs/convergence.md; minutes)
#   make check-hard  the hard-case suite tests/hard/ (docs/stability.md)
#   make check-default  the default Cusick scene, dynamic at 1 cm, must reach
#                  equilibrium (~150 s CPU; in CI)
#   make check-install  a staged install used from elsewhere, its man page,
#                  uninstall (in CI)
#   make bench-animate  the animate method against backward Euler
#   make validate  validation against analytic and reference solutions
#   make asan      ASan+UBSan build in build/asan, all suites + a small run
#   make valgrind  memcheck: drape check/run and the loader suites
#   make fuzz      fuzz the fabric and scene loaders (FUZZ_TIME=30 s each)
#   make install   install drape into $(DESTDIR)$(PREFIX)/bin (data, docs,
#                  drape.1 too; docs/install.md); make uninstall removes it
#   make clean

CC      ?= cc
# Installation (GNU conventions; `make install PREFIX=/opt/drape
# DESTDIR=/tmp/stage`): the binary, drape.1, the shipped data (read by the
# binary from DATADIR, compiled in; DRAPE_DATA overrides it) and the docs.
PREFIX  ?= /usr/local
BINDIR  ?= $(PREFIX)/bin
DATADIR ?= $(PREFIX)/share/drape
DOCDIR  ?= $(PREFIX)/share/doc/drape
MANDIR  ?= $(PREFIX)/share/man
MAN1DIR ?= $(MANDIR)/man1
CFLAGS  ?= -O3 -g
LDFLAGS ?=

DEB_PACKAGES = libgsl-dev libsundials-dev libsuitesparse-dev libhdf5-dev \
               libyaml-dev check pkg-config libopenblas-dev \
               libgeos-dev libjson-c-dev libxml2-dev librsvg2-dev help2man man-db

# Flags drape itself needs (not overridable: the language level is part of
# the code).  pkg-config is expanded lazily, so `make deps all` works on a
# machine that has none of the packages yet.
PKGS        = gsl yaml-0.1 hdf5-serial geos json-c
DRAPE_CPPFLAGS = -Iinclude -I/usr/include/suitesparse \
                 $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
DRAPE_CFLAGS = -std=c99 -D_POSIX_C_SOURCE=200809L -Wall -Wextra \
               -Wmissing-prototypes -Wstrict-prototypes -Wshadow
# SUNDIALS 6.4.1 and KLU ship no .pc files: link them by name.  GSL's BLAS
# is OpenBLAS, not the reference gslcblas (numerics.md, section 2).
DRAPE_LIBS  = -lsundials_arkode -lsundials_cvode -lsundials_kinsol \
              -lsundials_nvecserial -lsundials_sunmatrixsparse \
              -lsundials_sunlinsolklu -lsundials_sunlinsolspgmr \
              -lklu -lcholmod -lsuitesparseconfig \
              -lgsl -lopenblas \
              $(shell pkg-config --libs yaml-0.1 hdf5-serial geos json-c 2>/dev/null) \
              $(shell pkg-config --libs librsvg-2.0 cairo 2>/dev/null) -lm
# librsvg and cairo draw shadow.png from shadow.svg (output_png.c); their
# headers (glib's among them) are given to that file only.
RSVG_CFLAGS = $(shell pkg-config --cflags librsvg-2.0 cairo 2>/dev/null)
# The tests also parse drape's SVG pictures with libxml2 and read its PNG
# pictures back with cairo.
CHECK_CFLAGS = $(shell pkg-config --cflags check libxml-2.0 cairo 2>/dev/null)
CHECK_LIBS   = $(shell pkg-config --libs check libxml-2.0 cairo 2>/dev/null)

ALL_CFLAGS = $(DRAPE_CPPFLAGS) $(DRAPE_CFLAGS) $(CPPFLAGS) $(CFLAGS)

# Objects go to $(O) (default build/); `make O=/tmp/x LIB_SRC=... TEST_SRC=...
# unit` builds and runs a subset of the suites out of tree.
O        ?= build
LIB_SRC  ?= $(filter-out src/main.c src/cli_%.c,$(wildcard src/*.c))
CLI_SRC  ?= src/main.c $(wildcard src/cli_*.c)
TEST_SRC ?= $(wildcard tests/check_*.c)
LIB_OBJ  = $(LIB_SRC:%.c=$(O)/%.o)
CLI_OBJ  = $(CLI_SRC:%.c=$(O)/%.o)
TEST_HELPERS = tests/testutil.c tests/elastica.c tests/fixture.c
TEST_OBJ = $(TEST_SRC:%.c=$(O)/%.o) $(O)/tests/runner.o $(TEST_HELPERS:%.c=$(O)/%.o)
HEADERS  = $(wildcard include/drape/*.h src/*.h)

.PHONY: all deps run check unit validate check-slurm check-hard check-default bench bench-quick bench-anisotropy \
        bench-ensemble bench-convergence bench-animate check-install \
        asan valgrind fuzz install uninstall clean FORCE

all: drape

deps:
	@missing=""; for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'ok installed' || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $$missing; \
	else echo "all Debian packages present"; fi

$(O)/libdrape.a: $(LIB_OBJ)
	rm -f $@ && $(AR) rcs $@ $(LIB_OBJ)

drape: $(CLI_OBJ) $(O)/libdrape.a
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $(CLI_OBJ) $(O)/libdrape.a $(DRAPE_LIBS)

# A private binary for out-of-tree work: make O=/tmp/x /tmp/x/drape
$(O)/drape: $(CLI_OBJ) $(O)/libdrape.a
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $(CLI_OBJ) $(O)/libdrape.a $(DRAPE_LIBS)

$(O)/src/%.o: src/%.c $(HEADERS)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -c -o $@ $<

$(O)/src/output_png.o: ALL_CFLAGS += $(RSVG_CFLAGS)

# The compiled-in data directory (src/cli_data.h): rewritten only when
# DATADIR changes, so `make install PREFIX=...` rebuilds what depends on it.
$(O)/gen/datadir.gen.h: FORCE
	@mkdir -p $(dir $@)
	@printf '#define DRAPE_DATADIR "%s"\n' '$(DATADIR)' > $@.tmp; \
	if cmp -s $@.tmp $@; then rm -f $@.tmp; else mv $@.tmp $@; fi
$(O)/src/cli_data.o: $(O)/gen/datadir.gen.h src/cli_data.h
$(O)/src/cli_data.o: ALL_CFLAGS += -I$(O)/gen
FORCE:

$(O)/tests/%.o: tests/%.c $(HEADERS) tests/testutil.h tests/elastica.h tests/fixture.h $(O)/tests/suites.gen.h
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(TEST_FEATURES) $(CHECK_CFLAGS) -I$(O)/tests -c -o $@ $<

# Two suites interpose a library function (a SUNDIALS restart, a CHOLMOD
# solve) that they make fail and otherwise pass on with dlsym(RTLD_NEXT),
# a GNU extension: only their objects see _GNU_SOURCE.
$(O)/tests/check_integrator.o $(O)/tests/check_animate.o $(O)/tests/check_specimens_resume.o: TEST_FEATURES = -D_GNU_SOURCE

# The runner learns the suites from the file names: tests/check_NOUN.c
# exports `Suite *NOUN_suite(void)`.
$(O)/tests/suites.gen.h: $(TEST_SRC) Makefile
	@mkdir -p $(dir $@)
	@{ for f in $(TEST_SRC); do n=$$(basename $$f .c); n=$${n#check_}; \
	   echo "SUITE($$n)"; done; } > $@.tmp && mv $@.tmp $@

$(O)/tests/check_drape: $(TEST_OBJ) $(O)/libdrape.a
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $(TEST_OBJ) $(O)/libdrape.a $(DRAPE_LIBS) $(CHECK_LIBS)

run: drape
	./drape run scenes/cusick.yaml

# Tests run from tests/ so they find ../scenes, ../fabrics and ../drape.
# The suites call the library in-process: OMP_THREAD_LIMIT=1 runs CHOLMOD's
# supernodal kernels in one thread, as drape itself does (src/main.c).
check: drape $(O)/tests/check_drape
	cd tests && OMP_THREAD_LIMIT=1 DRAPE_BIN=$(abspath drape) $(abspath $(O))/tests/check_drape

unit: $(O)/tests/check_drape
	cd tests && OMP_THREAD_LIMIT=1 $(abspath $(O))/tests/check_drape

# Benchmarks: wall time, steps and DC per integrator (docs/integrators.md).
bench-quick: drape
	scripts/bench-quick.sh

# Work-precision report (docs/performance.md).
bench: drape
	scripts/bench.sh

# Accurate against fast drape-test ensembles (docs/ensemble.md).
bench-ensemble: drape
	scripts/bench-ensemble.sh

# The drape test against the lattice spacing (docs/convergence.md; hours
# of CPU: resumable, see scripts/bench-convergence.sh).
bench-convergence: drape
	scripts/bench-convergence.sh

# The lattice's preference for folds on its diagonals, in the bending
# energy of a smooth skirt of the isotropic study fabric
# (scripts/lattice-anisotropy.c, docs/convergence.md)
$(O)/lattice-anisotropy: scripts/lattice-anisotropy.c $(O)/libdrape.a
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $< $(O)/libdrape.a $(DRAPE_LIBS)

# One fold state put on the lattice turned by 10 and 45 degrees, relaxed
# (scripts/lattice-turn.c, docs/convergence.md): minutes of CPU
$(O)/lattice-turn: scripts/lattice-turn.c $(O)/libdrape.a
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $< $(O)/libdrape.a $(DRAPE_LIBS)

bench-anisotropy: $(O)/lattice-anisotropy $(O)/lattice-turn
	$(O)/lattice-anisotropy scenes/cusick.yaml docs/performance/convergence/isotropic-plate.yaml \
	    0.01 0.007 0.005 0.0035 0.0025 0.00125
	OPENBLAS_NUM_THREADS=1 $(O)/lattice-turn scenes/cusick.yaml \
	    docs/performance/convergence/isotropic-plate.yaml 2 0.005 0.01 0.007 0.005

# The animate method against backward Euler, and where its time goes
# (docs/animate.md).
bench-animate: drape
	scripts/bench-animate.sh

# The default scene to equilibrium, the way it asks.
check-default: drape
	scripts/check-default.sh

# Hard cases: each finishes bounded or fails with a diagnosis (docs/stability.md).
check-hard: drape
	scripts/check-hard.sh

# Reliability (docs/reliability.md); the scripts install valgrind and clang
# themselves when missing.
asan:
	scripts/asan.sh

valgrind: drape $(O)/tests/check_drape
	O=$(O) scripts/valgrind.sh

fuzz:
	scripts/fuzz.sh

# Validation against analytic and reference solutions (docs/validation.md).
validate: drape
	scripts/validate.sh

# Slurm job array scripts against a real single-node Slurm (docs/batch.md).
check-slurm: drape
	scripts/check-slurm.sh

# The manual page, generated from --help (scripts/man.sh, help2man).
$(O)/drape.1: $(O)/drape scripts/man.sh README.md
	scripts/man.sh $(O)/drape README.md $(DATADIR) $(DOCDIR) > $@.tmp && mv $@.tmp $@

DATA_FILES = $(wildcard fabrics/*.yaml scenes/*.yaml)
DOC_FILES  = README.md $(shell find docs -type f | LC_ALL=C sort)

# (the installed binary is $(O)/drape, the same objects as ./drape, so
# that `make install O=... PREFIX=...` leaves the checkout's ./drape alone)
install: $(O)/drape $(O)/drape.1
	install -d "$(DESTDIR)$(BINDIR)" "$(DESTDIR)$(MAN1DIR)"
	install -m 755 $(O)/drape "$(DESTDIR)$(BINDIR)/drape"
	install -m 644 $(O)/drape.1 "$(DESTDIR)$(MAN1DIR)/drape.1"
	@for f in $(DATA_FILES); do \
	  install -D -m 644 "$$f" "$(DESTDIR)$(DATADIR)/$$f" || exit 1; done
	@for f in $(DOC_FILES); do \
	  install -D -m 644 "$$f" "$(DESTDIR)$(DOCDIR)/$$f" || exit 1; done
	@echo "installed drape in $(DESTDIR)$(BINDIR), data in $(DESTDIR)$(DATADIR)," \
	  "docs in $(DESTDIR)$(DOCDIR), drape.1 in $(DESTDIR)$(MAN1DIR)"

# Exactly what install wrote (the same lists), then drape's own
# directories left empty: the trees fabrics/, scenes/ (DATADIR) and docs/
# (DOCDIR), then DATADIR and DOCDIR themselves if empty.  Only those:
# DATADIR and DOCDIR may be shared directories such as /usr/share/doc,
# whose other empty directories are not drape's to remove.
uninstall:
	rm -f "$(DESTDIR)$(BINDIR)/drape" "$(DESTDIR)$(MAN1DIR)/drape.1"
	@for f in $(DATA_FILES); do rm -f "$(DESTDIR)$(DATADIR)/$$f"; done
	@for f in $(DOC_FILES); do rm -f "$(DESTDIR)$(DOCDIR)/$$f"; done
	@for d in "$(DESTDIR)$(DATADIR)/fabrics" "$(DESTDIR)$(DATADIR)/scenes" \
	          "$(DESTDIR)$(DOCDIR)/docs"; do \
	  if [ -d "$$d" ]; then find "$$d" -depth -type d -empty -delete; fi; done
	@rmdir "$(DESTDIR)$(DATADIR)" "$(DESTDIR)$(DOCDIR)" 2>/dev/null || :

# A staged install (DESTDIR) used from another directory, its manual
# page rendered, and the uninstall (scripts/check-install.sh).
check-install: drape
	scripts/check-install.sh

clean:
	rm -rf drape build
