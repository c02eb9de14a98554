# Breccia: one entry point for people and CI.
#   make demo   - the default case end to end (concrete block with a charge hole)
#   make test   - build and run the test suite
#   make package - the .deb (CPack), breccia_<version>_<arch>.deb in $(BUILD)
# Both install the Debian packages they need first (make deps).
BUILD    ?= build
JOBS     ?= $(shell nproc)
CUDA     ?= AUTO
NATIVE   ?= OFF
PYTHON   ?= /usr/bin/python3
QUICK    ?=
export PYTHON

.PHONY: all deps configure build test test-serial-hdf5 test-sanitize compile-serial-hdf5 demo bench bench-pipeline clean help lammps-peri package check-package install

all: build

help:
	@echo "make deps | build | test | test-serial-hdf5 | test-sanitize | compile-serial-hdf5 | demo | bench | case-NAME [QUICK=1] | install PREFIX=P | package | check-package | clean"

deps:
	@bash scripts/install-deps.sh

# Configured every time, after deps (a few seconds when nothing changed): NATIVE=ON or CUDA=...
# given to a later make take effect, and a configure that failed half-way (it leaves a
# CMakeCache.txt) runs again instead of being skipped. Under make -j the configure waits for
# deps (it ran while the packages were still being installed when the cache was its target).
configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DBRECCIA_CUDA=$(CUDA) -DBRECCIA_NATIVE=$(NATIVE)

build: configure
	cmake --build $(BUILD) -j $(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 900

# make test-serial-hdf5: the distributed tests in a second build folder with MPI and the serial
# HDF5 (rank 0 gathers and writes every file), the path make test's build (parallel HDF5) does
# not take; no CUDA (docs/parallel.md, "One HDF5 per process"). CI runs it (.ci/run): the
# path's files once differed from one process's unnoticed while only its compilation was
# checked. The tests that compare files (test_distributed); the unit tests of test_solver do
# not depend on the HDF5.
SERIAL_HDF5_BUILD ?= $(BUILD)-serial-hdf5
test-serial-hdf5: deps
	cmake -S . -B $(SERIAL_HDF5_BUILD) -DCMAKE_BUILD_TYPE=Release -DBRECCIA_CUDA=OFF -DBRECCIA_NATIVE=$(NATIVE) \
	  -DHDF5_C_COMPILER_EXECUTABLE=/usr/bin/h5cc
	cmake --build $(SERIAL_HDF5_BUILD) -j $(JOBS) --target breccia-solve breccia-mesh breccia-place test_distributed
	ldd $(SERIAL_HDF5_BUILD)/bin/breccia-solve | grep -q libhdf5_serial || { echo "$(SERIAL_HDF5_BUILD): not the serial HDF5"; exit 1; }
	cd $(SERIAL_HDF5_BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 900 -R "Distributed|SameAnswer"

# make test-sanitize: the test suite under AddressSanitizer and UndefinedBehaviorSanitizer in
# a third build folder (RelWithDebInfo, no CUDA), the case tests (cases.*) left out for their
# length. Any out-of-bounds access, use after free or undefined behaviour stops its test with
# the report. Leaks are not checked: gmsh, VTK and HDF5 keep memory to the end by design. Not in
# CI: on 2 cores the build took 32 minutes and the tests 23 (2026-12-07, 586 tests, all passed,
# no sanitizer report).
SANITIZE_BUILD ?= $(BUILD)-sanitize
SANITIZE_FLAGS = -fsanitize=address,undefined -fno-omit-frame-pointer
test-sanitize: deps
	cmake -S . -B $(SANITIZE_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBRECCIA_CUDA=OFF -DBRECCIA_NATIVE=OFF \
	  "-DCMAKE_CXX_FLAGS=$(SANITIZE_FLAGS)" "-DCMAKE_C_FLAGS=$(SANITIZE_FLAGS)" \
	  "-DCMAKE_EXE_LINKER_FLAGS=$(SANITIZE_FLAGS)" "-DCMAKE_SHARED_LINKER_FLAGS=$(SANITIZE_FLAGS)"
	cmake --build $(SANITIZE_BUILD) -j $(JOBS)
	cd $(SANITIZE_BUILD) && ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS) --timeout 900 -E "^cases\."

# make compile-serial-hdf5: only the sources whose code differs with a serial HDF5
# (BRECCIA_PARALLEL_HDF5 unset) compiled in that folder, no link, no tests: a cheap check that
# the serial path still compiles (make test's build takes the parallel HDF5); CI runs the
# fuller make test-serial-hdf5, which builds and runs its tests.
compile-serial-hdf5: deps
	cmake -S . -B $(SERIAL_HDF5_BUILD) -DCMAKE_BUILD_TYPE=Release -DBRECCIA_CUDA=OFF -DBRECCIA_NATIVE=$(NATIVE) \
	  -DHDF5_C_COMPILER_EXECUTABLE=/usr/bin/h5cc
	! grep -q BRECCIA_PARALLEL_HDF5 $(SERIAL_HDF5_BUILD)/common/CMakeFiles/breccia_common.dir/flags.make || \
	  { echo "$(SERIAL_HDF5_BUILD): configured with the parallel HDF5, not the serial one"; exit 1; }
	$(MAKE) -C $(SERIAL_HDF5_BUILD)/common src/h5.o
	$(MAKE) -C $(SERIAL_HDF5_BUILD)/solver src/rank_system.o src/outputs.o src/distributed_setup.o mpi/src/mpi_backend.o
	$(MAKE) -C $(SERIAL_HDF5_BUILD)/tests/solver test_partition.o

demo: build
	bash scripts/run_case.sh $(BUILD) cases/concrete-blast $(if $(QUICK),quick,demo)

case-%: build
	bash scripts/run_case.sh $(BUILD) cases/$* $(if $(QUICK),quick,full)

# make install PREFIX=P: the tools, cases, chart scripts, planner data and docs under P
# (README.md, "Install"); the tools find their data from their own location.
PREFIX ?= /usr/local
install: build
	cmake --install $(BUILD) --prefix $(PREFIX)

# make package: the .deb of the same layout under /usr (cmake/BrecciaPackage.cmake).
package: build
	cmake --build $(BUILD) --target package

# make check-package: the .deb unpacked into an empty folder and the quick demo run from it alone.
check-package: build
	bash scripts/check-package.sh $(BUILD)

bench: build
	bash scripts/bench.sh $(BUILD)
	bash scripts/bench_mpi.sh $(BUILD)
	bash scripts/bench_pipeline.sh $(BUILD)

# make bench-pipeline: the concrete case from specimen to post-processing, each stage timed, at
# the demo and full resolution (docs/performance.md, "The whole chain"); SIZES=demo for one
bench-pipeline: build
	bash scripts/bench_pipeline.sh $(BUILD)

# make bench-mpi: strong scaling of a distributed run, 1 -> 2 ranks beside LAMMPS (docs/parallel.md)
bench-mpi: build
	bash scripts/bench_mpi.sh $(BUILD)

# make lammps-peri: LAMMPS PERI's own projectile examples run in LAMMPS and in Breccia with
# each of LAMMPS's modelling choices on and off, plus a time-step study
# -> runs/lammps-peri/comparison.md, dt_study.md, pmb.png, lps.png (docs/lammps-peri.md).
.PHONY: lammps-peri
lammps-peri: build
	bash scripts/lammps_peri.sh $(BUILD) --dt-study

clean:
	rm -rf $(BUILD)

# make atlas [QUICK=1]: speed-accuracy sweeps and the measured stability map of the PD solver
# -> docs/atlas/atlas.csv, docs/atlas/stability.csv (+ stability_graded.csv, stability_mps.csv),
#    docs/atlas/*.png, docs/atlas.md.
# QUICK=1: ~6 min on 2 quiet cores (measured in pieces), ~15 min on the shared machine; full: not yet run.
.PHONY: atlas
atlas: build
	$(BUILD)/bin/breccia-atlas $(if $(QUICK),--quick) --threads $(JOBS) --work runs/atlas \
	  --csv docs/atlas/atlas.csv --stability-csv docs/atlas/stability.csv
	$(PYTHON) scripts/atlas_charts.py --csv docs/atlas/atlas.csv --stability docs/atlas/stability.csv \
	  --out docs --command "make atlas$(if $(QUICK), QUICK=1)"
