# Breccia: one entry point for people and CI.
#   make demo   - the default case end to end (concrete block with a charge hole)
#   make test   - build and run the test suite
# Both install the Debian packages they need first (make deps).
BUILD    ?= build
JOBS     ?= $(shell nproc)
CUDA     ?= AUTO
PYTHON   ?= /usr/bin/python3
QUICK    ?=
export PYTHON

.PHONY: all deps configure build test demo bench clean help

all: build

help:
	@echo "make deps | build | test | demo | bench | case-NAME [QUICK=1] | clean"

deps:
	@bash scripts/install-deps.sh

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DBRECCIA_CUDA=$(CUDA)

configure: deps $(BUILD)/CMakeCache.txt

build: configure
	cmake --build $(BUILD) -j $(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 900

demo: build
	bash scripts/run_case.sh $(BUILD) cases/concrete-blast $(if $(QUICK),quick,demo)

case-%: build
	bash scripts/run_case.sh $(BUILD) cases/$* $(if $(QUICK),quick,full)

bench: build
	bash scripts/bench.sh $(BUILD)

clean:
	rm -rf $(BUILD)
