# pd -- peridynamics toolkit.  GNU make.
#
#   make            build programs and libpd
#   make check      install missing Debian packages (as root), build, run all tests
#   make demo       the seed impact example end to end (ParaView files + PNG)
#   make bench      pd-run against LAMMPS on the seed impact
#   make install PREFIX=/usr/local DESTDIR=
#
# The project's own flags are kept apart from CFLAGS, so a user's CFLAGS
# (say -O0 -g) still works.

PREFIX    ?= /usr/local
BINDIR     = $(PREFIX)/bin
LIBDIR     = $(PREFIX)/lib
INCDIR     = $(PREFIX)/include
MANDIR     = $(PREFIX)/share/man
PCDIR      = $(LIBDIR)/pkgconfig
SHAREDIR   = $(PREFIX)/share/pd

CC        ?= cc
CFLAGS    ?= -O3 -g
# Serial HDF5 by name: with Debian's libhdf5-openmpi-dev installed too, the
# plain `hdf5` of pkg-config is the MPI one.
HDF5_PC   := $(shell pkg-config --exists hdf5-serial 2>/dev/null && echo hdf5-serial || echo hdf5)
PD_CFLAGS  = -std=c11 -D_POSIX_C_SOURCE=200809L -Wall -Wextra -fopenmp -fno-math-errno -Ilib \
             $(shell pkg-config --cflags $(HDF5_PC) gsl zlib 2>/dev/null)
PD_LIBS    = $(shell pkg-config --libs $(HDF5_PC) gsl zlib 2>/dev/null) -fopenmp -lm

# The MPI build of pd-run and pd-bonds (mpi/bin/, its objects under mpi/): with
# Open MPI's mpicc and parallel HDF5 (Debian's libhdf5-openmpi-dev).  MPI=1
# asks for it, MPI=0 leaves it out; by default it is built when both are
# there.  The serial build never needs MPI.
MPICC     ?= mpicc
MPI_FOUND := $(shell command -v $(MPICC) >/dev/null 2>&1 && pkg-config --exists hdf5-openmpi 2>/dev/null && echo 1)
MPI       ?= $(if $(MPI_FOUND),1,0)
MPI_CFLAGS = -std=c11 -D_POSIX_C_SOURCE=200809L -Wall -Wextra -fopenmp -fno-math-errno -Ilib \
             -DPD_MPI=1 $(shell pkg-config --cflags hdf5-openmpi gsl zlib 2>/dev/null)
MPI_LIBS   = $(shell pkg-config --libs hdf5-openmpi gsl zlib 2>/dev/null) -fopenmp -lm

ifeq ($(SANITIZE),1)
PD_CFLAGS += -fsanitize=address,undefined -fno-omit-frame-pointer
PD_LIBS   += -fsanitize=address,undefined
MPI_CFLAGS += -fsanitize=address,undefined -fno-omit-frame-pointer
MPI_LIBS   += -fsanitize=address,undefined
# tests that cannot run with the sanitizers (valgrind) skip themselves
export PD_SANITIZE = 1
endif

C_PROGRAMS = $(patsubst cmd/%.c,%,$(wildcard cmd/pd-*.c))
PY_PROGRAMS = $(patsubst cmd/%.py,%,$(wildcard cmd/pd-*.py))
PROGRAMS   = $(C_PROGRAMS) $(PY_PROGRAMS)
LIB_LAYERS = $(shell cat lib/LAYERS)
LIB_SRC    = $(foreach l,$(LIB_LAYERS),$(wildcard lib/$(l)/*.c))
LIB_HDR    = lib/pd.h $(wildcard lib/*/*.h)
LIB_OBJ    = $(LIB_SRC:.c=.o)
BIN        = $(addprefix bin/,$(PROGRAMS))
UNIT_SRC   = $(wildcard tests/unit/*.c)
UNIT_BIN   = $(UNIT_SRC:tests/unit/%.c=bin/test-%)
MPI_OBJ    = $(LIB_SRC:%.c=mpi/%.o)
MPI_BIN    = $(if $(filter 1,$(MPI)),mpi/bin/pd-run mpi/bin/pd-bonds)

.PHONY: all check test layers unit bats deps demo bench fuzz install uninstall clean

all: $(BIN) lib/libpd.a $(MPI_BIN)

lib/%.o: lib/%.c $(LIB_HDR)
	$(CC) $(PD_CFLAGS) $(CFLAGS) -c -o $@ $<

# The bond kernel may reassociate its per-particle sums so that they
# vectorize (the order is fixed per instruction set, not per thread count).
VEC_CFLAGS = -fassociative-math -fno-signed-zeros -fno-trapping-math
lib/models/pmb.o lib/effects/contact.o: PD_CFLAGS += $(VEC_CFLAGS)
# The stencil's segment loops vectorize without a processor's masked
# division only when a division may be done speculatively: no trapping
# math there, which changes no value (only the floating-point exception
# flags, which pd never reads), so its bits stay those of the scalar loop.
lib/stencil/grid_pmb.o lib/stencil/grid_energy.o lib/stencil/grid_lps.o: PD_CFLAGS += -fno-trapping-math

lib/libpd.a: $(LIB_OBJ)
	rm -f $@
	ar rcs $@ $^

mpi/lib/%.o: lib/%.c $(LIB_HDR)
	@mkdir -p $(dir $@)
	$(MPICC) $(MPI_CFLAGS) $(CFLAGS) -c -o $@ $<
mpi/lib/models/pmb.o mpi/lib/effects/contact.o: MPI_CFLAGS += $(VEC_CFLAGS)
mpi/lib/stencil/grid_pmb.o mpi/lib/stencil/grid_energy.o mpi/lib/stencil/grid_lps.o: MPI_CFLAGS += -fno-trapping-math

mpi/libpd.a: $(MPI_OBJ)
	rm -f $@
	ar rcs $@ $^

mpi/bin/%: cmd/%.c cmd/cli.h mpi/libpd.a $(LIB_HDR)
	@mkdir -p mpi/bin
	$(MPICC) $(MPI_CFLAGS) $(CFLAGS) -o $@ $< mpi/libpd.a $(MPI_LIBS)

bin/%: cmd/%.c cmd/cli.h lib/libpd.a $(LIB_HDR)
	@mkdir -p bin
	$(CC) $(PD_CFLAGS) $(CFLAGS) -o $@ $< lib/libpd.a $(PD_LIBS)

# The Python programs (pd-mesh, on meshio) run under Debian's python3,
# with the version of lib/pd.h.
bin/%: cmd/%.py lib/pd.h
	@mkdir -p bin
	sed -e "s/@VERSION@/$$(sed -n 's/^#define PD_VERSION "\(.*\)"/\1/p' lib/pd.h)/" $< > $@.tmp
	chmod 755 $@.tmp
	mv $@.tmp $@

# The bench's timing of the bond kernel alone (share/bench.sh, "passes").
share/passes: share/passes.c lib/libpd.a $(LIB_HDR)
	$(CC) $(PD_CFLAGS) $(CFLAGS) -o $@ $< lib/libpd.a $(PD_LIBS)

bin/test-%: tests/unit/%.c tests/unit/check.h lib/libpd.a $(LIB_HDR)
	@mkdir -p bin
	$(CC) $(PD_CFLAGS) $(CFLAGS) -o $@ $< lib/libpd.a $(PD_LIBS)

deps:
	@sh share/install-deps.sh

check: deps
	$(MAKE) all $(UNIT_BIN) share/passes
	$(MAKE) test

test: layers unit bats

# lib/ calls only downward: its folders are layers (lib/LAYERS, bottom
# first; lib/README.md), read from the objects' symbols.
layers: lib/libpd.a
	@sh share/layers.sh

unit: $(UNIT_BIN)
	@for t in $(UNIT_BIN); do echo "$$t"; $$t || exit 1; done

# Tests run one program at a time on a shared machine: threads that sleep
# when idle keep a busy 2-core machine from spinning.
bats: all
	OMP_WAIT_POLICY=passive bats tests/

demo: deps
	$(MAKE) all
	$(MAKE) -C examples/lammps-impact demo

bench: deps
	$(MAKE) all share/passes
	sh share/bench.sh

# The readers under libFuzzer (clang), AddressSanitizer and UBSan for
# FUZZ_SECONDS; tests/fuzz/fuzz_readers.c says what is fuzzed.  OpenMP is
# left out of this build (its pragmas are ignored).
FUZZ_SECONDS ?= 60
FUZZ_CC      ?= clang
fuzz:
	@sh share/install-deps.sh clang libclang-rt-14-dev
	@mkdir -p bin tests/fuzz/corpus
	$(FUZZ_CC) -std=c11 -D_POSIX_C_SOURCE=200809L -g -O1 -Wno-unknown-pragmas \
	    -fsanitize=fuzzer,address,undefined -fno-math-errno -Ilib \
	    $(shell pkg-config --cflags $(HDF5_PC) gsl) -o bin/fuzz-readers tests/fuzz/fuzz_readers.c \
	    $(LIB_SRC) $(shell pkg-config --libs $(HDF5_PC) gsl) -lm
	bin/fuzz-readers -max_total_time=$(FUZZ_SECONDS) -timeout=10 -len_control=0 -max_len=512 \
	    tests/fuzz/corpus

install: all
	install -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(LIBDIR) $(DESTDIR)$(INCDIR) $(DESTDIR)$(PCDIR) \
	    $(DESTDIR)$(MANDIR)/man1 $(DESTDIR)$(MANDIR)/man5 $(DESTDIR)$(MANDIR)/man7 \
	    $(DESTDIR)$(SHAREDIR)/python
	install -m 755 $(BIN) $(DESTDIR)$(BINDIR)
	$(if $(MPI_BIN),install -m 755 $(MPI_BIN) $(DESTDIR)$(BINDIR))
	install -m 644 lib/libpd.a $(DESTDIR)$(LIBDIR)
	install -m 644 lib/pd.h $(DESTDIR)$(INCDIR)
	install -m 644 man/man1/*.1 $(DESTDIR)$(MANDIR)/man1
	install -m 644 man/man5/*.5 $(DESTDIR)$(MANDIR)/man5
	install -m 644 man/man7/*.7 $(DESTDIR)$(MANDIR)/man7
	install -m 644 share/pdh5.py share/pdcost.py $(DESTDIR)$(SHAREDIR)/python
	install -m 644 share/cost.gp $(DESTDIR)$(SHAREDIR)
	sed -e 's|@PREFIX@|$(PREFIX)|' -e 's|@HDF5@|$(HDF5_PC)|' share/pd.pc.in > $(DESTDIR)$(PCDIR)/pd.pc

uninstall:
	rm -f $(addprefix $(DESTDIR)$(BINDIR)/,$(PROGRAMS))
	rm -f $(DESTDIR)$(LIBDIR)/libpd.a $(DESTDIR)$(INCDIR)/pd.h $(DESTDIR)$(PCDIR)/pd.pc
	rm -f $(addprefix $(DESTDIR)$(MANDIR)/man1/,$(addsuffix .1,$(PROGRAMS)))
	rm -f $(DESTDIR)$(MANDIR)/man5/pd-h5.5 $(DESTDIR)$(MANDIR)/man7/pd.7
	rm -f $(DESTDIR)$(SHAREDIR)/python/pdh5.py $(DESTDIR)$(SHAREDIR)/python/pdcost.py \
	    $(DESTDIR)$(SHAREDIR)/cost.gp
	-rmdir $(DESTDIR)$(SHAREDIR)/python $(DESTDIR)$(SHAREDIR) 2>/dev/null

clean:
	rm -rf bin lib/*/*.o lib/libpd.a mpi share/passes
