# The two set-up commands of the README (`make demo`, `make test`) and friends.
# Every target installs missing Debian packages first (scripts/install-deps.sh
# is idempotent and quick when everything is present).
JOBS      ?= 2
BUILD     ?= build
ASAN      ?= build-asan
CMAKEFLAGS ?=
ifeq ($(CI),true)
  CMAKEFLAGS += -DPIEZO_WERROR=ON
endif

.PHONY: all deps configure build demo test test-asan bench validate clean fixtures screenshots

all: build

deps:
	@bash scripts/install-deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DPIEZO_WERROR=ON $(CMAKEFLAGS)

configure: deps $(BUILD)/CMakeCache.txt

build: configure
	cmake --build $(BUILD) -j$(JOBS)

demo: build
	./$(BUILD)/ui/piezobench demo

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) -LE validate

test-asan: deps
	cmake -S . -B $(ASAN) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPIEZO_SANITIZE=ON \
	      -DPIEZO_BUILD_BENCH=OFF -DPIEZO_WERROR=ON $(CMAKEFLAGS)
	cmake --build $(ASAN) -j$(JOBS)
	cd $(ASAN) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	      LSAN_OPTIONS=suppressions=$(CURDIR)/scripts/lsan-suppressions.txt \
	      ctest --output-on-failure -j$(JOBS) -LE validate

bench: build
	bash scripts/run-benchmarks.sh $(BUILD)

validate: build
	cd $(BUILD) && ctest --output-on-failure -L validate

# The GUI's screenshots in docs/ (headless, xvfb-run): scripts/gui-screenshots.sh.
screenshots: build
	bash scripts/gui-screenshots.sh $(BUILD)

fixtures: deps
	/usr/bin/python3 fixtures/make_fixtures.py fixtures

clean:
	rm -rf $(BUILD) $(ASAN)

# libFuzzer runs of the fuzz harnesses (tests/fuzz/README.md): a clang build
# with ASan + UBSan in $(FUZZ_BUILD), then FUZZ_SECONDS per harness; crashes
# are written to tests/fuzz/regressions/<name>/. `make test` needs none of
# this: it runs the same harnesses briefly with gcc (CTest label fuzz).
FUZZ_BUILD   ?= build-fuzz
FUZZ_SECONDS ?= 600
FUZZ_TARGETS ?= capture block_parser plan impedance_file touchstone hp4294a e4990a bode100 impedance_table hioki labone impedance_columns
.PHONY: fuzz
fuzz:
	@bash scripts/install-deps.sh fuzz
	cmake -S . -B $(FUZZ_BUILD) -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
	      -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPIEZO_FUZZ=ON -DBUILD_TESTING=OFF \
	      -DPIEZO_BUILD_GUI=OFF -DPIEZO_BUILD_BENCH=OFF
	nice -n 10 cmake --build $(FUZZ_BUILD) -j$(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	bash scripts/run-fuzz.sh $(FUZZ_BUILD) $(FUZZ_SECONDS) $(FUZZ_TARGETS)
