# Thin wrapper over CMake. `make demo` and `make test` do all their own set-up on a fresh machine.
BUILD     ?= build
JOBS      ?= $(shell nproc)
BUILD_TYPE ?= Release
# CI (CI=true in the environment) builds with -Werror.
WERROR    ?= $(if $(CI),ON,OFF)
CMAKE_FLAGS ?=
TETRAPAGE := $(BUILD)/tools/tetrapage
DEMO_DIR  ?= out/demo

# Exactly the Debian packages the project needs.
DEB_PACKAGES := cmake make g++ pkg-config \
  libeigen3-dev libcgal-dev libcgal-demo assimp-testmodels libgmp-dev libmpfr-dev libboost-dev \
  libhdf5-dev libtbb-dev libembree-dev libassimp-dev libcli11-dev nlohmann-json3-dev \
  libgtest-dev libbenchmark-dev libfcl-dev gnuplot-nox zlib1g-dev libdeflate-dev liblz4-dev hdf5-filter-plugin time python3 \
  pybind11-dev python3-dev python3-numpy python3-pytest python3-venv \
  libocct-data-exchange-dev libocct-ocaf-dev libocct-modeling-algorithms-dev libocct-modeling-data-dev \
  libocct-foundation-dev occt-misc freecad-common

# What `make bench-rack` needs besides: KiCad's STEP packages (about 1 GB; no test needs them).
RACK_PACKAGES := kicad-packages3d

# What `make fuzz` needs besides: clang and its libFuzzer and sanitizer runtimes.
FUZZ_PACKAGES := clang-14 libclang-rt-14-dev

.PHONY: deps fuzz-deps configure build test sanitize sanitize-threads fuzz demo bench bench-study bench-peers bench-peers-demo bench-accuracy bench-deflection bench-scale bench-rack clean format

# $(call install_missing,NAME,PACKAGES): installs those not present (sudo only when not root).
define install_missing
	@missing=""; for p in $(2); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -z "$$missing" ]; then echo "$(1): all $(words $(2)) packages present"; \
	else \
	  if [ "$$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi; \
	  echo "$(1): installing$$missing"; \
	  $$SUDO apt-get update -q && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -q --no-install-recommends $$missing; \
	fi
endef

deps:
	$(call install_missing,deps,$(DEB_PACKAGES))

fuzz-deps:
	$(call install_missing,fuzz-deps,$(FUZZ_PACKAGES))

configure: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) -DTETRAPAGE_WERROR=$(WERROR) $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD) -j $(JOBS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 1200
	$(MAKE) --no-print-directory sanitize-threads

# OpenCASCADE's and Assimp's own leaks (process-long registries) are not ours to fix; the file
# names each frame and why.
LSAN_SUPPRESSIONS := suppressions=$(CURDIR)/tests/sanitizers/lsan.supp

# Threads flying through one index, built and run under AddressSanitizer + UBSan (only the
# libraries that test needs, so that `make test` stays within CI's time).
sanitize-threads: configure
	cmake -S . -B $(BUILD)-asan -DCMAKE_BUILD_TYPE=asan -DTETRAPAGE_WERROR=$(WERROR) \
	  -DTETRAPAGE_BUILD_BENCH=OFF $(CMAKE_FLAGS)
	cmake --build $(BUILD)-asan --target runtime_threads_tests -j $(JOBS)
	cd $(BUILD)-asan && ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=$(LSAN_SUPPRESSIONS) \
	  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 ./tests/runtime/runtime_threads_tests

# The whole suite under AddressSanitizer + UBSan, and the threaded runtime tests under
# ThreadSanitizer (docs/RELIABILITY.md): about an hour on two cores, so run before each
# release tag rather than in CI. TBB is not built with TSan: its hand-overs are suppressed
# (tests/sanitizers/tsan.supp); the runtime's own threads stay checked. The longest history
# (history_size=7): with the default, the stack of a TBB worker's earlier write is lost, the
# suppression cannot match it, and an object model built in parallel_invoke and freed by the
# caller reads as a race.
sanitize: configure
	cmake -S . -B $(BUILD)-asan -DCMAKE_BUILD_TYPE=asan -DTETRAPAGE_WERROR=$(WERROR) \
	  -DTETRAPAGE_BUILD_BENCH=OFF $(CMAKE_FLAGS)
	cmake --build $(BUILD)-asan -j $(JOBS)
	cd $(BUILD)-asan && ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=$(LSAN_SUPPRESSIONS) \
	  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 ctest --output-on-failure -j $(JOBS) --timeout 3600
	cmake -S . -B $(BUILD)-tsan -DCMAKE_BUILD_TYPE=tsan -DTETRAPAGE_WERROR=$(WERROR) \
	  -DTETRAPAGE_BUILD_BENCH=OFF $(CMAKE_FLAGS)
	cmake --build $(BUILD)-tsan --target runtime_threads_tests -j $(JOBS)
	cd $(BUILD)-tsan && TSAN_OPTIONS="halt_on_error=1 history_size=7 suppressions=$(CURDIR)/tests/sanitizers/tsan.supp" \
	  ./tests/runtime/runtime_threads_tests

# libFuzzer on every reader of outside bytes (docs/RELIABILITY.md): built with clang, ASan and
# UBSan in $(FUZZ_BUILD), each target run FUZZ_SECONDS on its corpus; fails on a crash, whose
# input stays in $(FUZZ_BUILD)/fuzz/crashes/TARGET/. CI (.ci/run) runs every target a minute.
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= ply obj stl off gltf glb manifest pose answers obstacles index index_data step_scan
fuzz: deps fuzz-deps
	CC=clang-14 CXX=clang++-14 cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -g" \
	  -DTETRAPAGE_FUZZ=ON -DTETRAPAGE_BUILD_TESTS=OFF -DTETRAPAGE_BUILD_BENCH=OFF \
	  -DTETRAPAGE_WERROR=$(WERROR) $(CMAKE_FLAGS)
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	tests/fuzz/run_fuzzers.sh $(FUZZ_BUILD) $(FUZZ_SECONDS) $(FUZZ_TARGETS)

demo: build
	@mkdir -p $(DEMO_DIR)
	$(TETRAPAGE) generate scene --triangles 1000000 --seed 1 -o $(DEMO_DIR)/scene.ply
	$(TETRAPAGE) generate object --triangles 2000 -o $(DEMO_DIR)/object.ply
	$(TETRAPAGE) generate flight --env $(DEMO_DIR)/scene.ply --object $(DEMO_DIR)/object.ply \
	  --steps 10000 --seed 1 --displacement 0.005 -o $(DEMO_DIR)/flight.csv --answers $(DEMO_DIR)/answers.csv \
	  --report $(DEMO_DIR)/flight.json
	$(TETRAPAGE) replay $(DEMO_DIR)/scene.ply --object $(DEMO_DIR)/object.ply \
	  --path $(DEMO_DIR)/flight.csv --report $(DEMO_DIR)/replay.json
	$(TETRAPAGE) preprocess $(DEMO_DIR)/scene.ply -o $(DEMO_DIR)/scene.tpi \
	  --report $(DEMO_DIR)/preprocess.json
	$(TETRAPAGE) validate $(DEMO_DIR)/scene.tpi
	$(TETRAPAGE) inspect $(DEMO_DIR)/scene.tpi
	$(TETRAPAGE) check-location $(DEMO_DIR)/scene.tpi --points 200000 --report $(DEMO_DIR)/location.json
	$(TETRAPAGE) check-interiors $(DEMO_DIR)/scene.tpi $(DEMO_DIR)/scene.ply --points 100000 --report $(DEMO_DIR)/interiors.json
	@echo "--- paged flight: a shard budget of 8 MiB, well under the index's shards ---"
	$(TETRAPAGE) fly $(DEMO_DIR)/scene.tpi --object $(DEMO_DIR)/object.ply --path $(DEMO_DIR)/flight.csv \
	  --memory 8M --check $(DEMO_DIR)/answers.csv --report $(DEMO_DIR)/fly.json
	$(TETRAPAGE) render $(DEMO_DIR)/scene.tpi -o $(DEMO_DIR)/page-ins.png --path $(DEMO_DIR)/flight.csv \
	  --object $(DEMO_DIR)/object.ply --color page-ins --memory 8M

bench: build
	@mkdir -p $(BUILD)/bench-results
	for b in formats geometry index shard walk cache; do \
	  $(BUILD)/bench/tetrapage_bench_$$b --benchmark_out=$(BUILD)/bench-results/$$b.json \
	    --benchmark_out_format=json || exit 1; \
	done
	$(MAKE) --no-print-directory bench-study bench-accuracy bench-peers bench-peers-demo bench-scale

# The study's flight benchmark: its environment groups x its six objects, the four methods, the
# hybrid (in memory and paged under 1 MiB) and the peers; tables and plots for docs/BENCHMARKS.md.
# Long (an hour or more); STUDY_FLAGS=--quick for a short run.
bench-study: build
	$(BUILD)/bench/tetrapage_bench_study --out $(BUILD)/bench-results/study --memory 1M $(STUDY_FLAGS)

# The out-of-core scale series (issue 8): generated scenes of SCALE_SIZES triangles and a terrain,
# preprocessed (automatic region size) and flown under budgets from 64 MiB to everything
# resident; scale.md and plots. The 100M scene needs about 10 GB of disk and half an hour.
SCALE_SIZES ?= 1000000 10000000 50000000 100000000
bench-scale: build
	TETRAPAGE=$(TETRAPAGE) TERRAIN=10000000 bench/scripts/scale_series.sh $(BUILD)/bench-results/scale $(SCALE_SIZES)

# FCL, CGAL's AABB tree and tetrapage (in memory, and paged under 10 % of the index) on data
# the project did not generate (issue 25): CGAL's meshes in 1M and 5M scenes, the 1201 x 1201
# terrain, a scene of Debian's assimp-testmodels, x the tetrahedron, CGAL's sphere, elk and lion;
# 10,000-pose flights, median of 5 passes; peers.md in $(BUILD)/bench-results/peers-foreign,
# whose generated data the next run reuses. STEPS, REPEATS, ENVS, OBJECTS, SCENE_SIZES, ... shrink
# it (bench/scripts/peers_foreign.sh).
bench-peers: build
	BUILD=$(BUILD) bench/scripts/peers_foreign.sh $(BUILD)/bench-results/peers-foreign

# The same harness on the demo's scene, the study's object sizes, 10,000-pose flights, paged under
# 8 MiB, 3 repetitions (docs/BENCHMARKS.md, "Peers").
bench-peers-demo: build
	@test -f $(DEMO_DIR)/scene.tpi || $(MAKE) --no-print-directory demo
	BUILD=$(BUILD) bench/scripts/peers_series.sh $(DEMO_DIR) $(BUILD)/bench-results/peers 8M 3

# Real CAD parts (issue 26): racks of boards populated with KiCad's STEP packages, of RACK_SIZES
# triangles; generate, preprocess (STEP read, tessellation, index), a connector's insertion and a
# billiard flight in memory and paged, FCL and CGAL beside; rack.md in $(BUILD)/bench-results/rack.
RACK_SIZES ?= 1000000 10000000
bench-rack: build
	$(call install_missing,bench-rack,$(RACK_PACKAGES))
	BUILD=$(BUILD) SIZES="$(RACK_SIZES)" bench/scripts/rack_series.sh $(BUILD)/bench-results/rack

# Speed against accuracy on the demo's scene and object (both indexes built, without interiors):
# every accuracy x shape x motion x storage on a billiard and a grazing flight, a Pareto plot.
bench-accuracy: build
	@test -f $(DEMO_DIR)/scene.tpi || $(MAKE) --no-print-directory demo
	$(BUILD)/bench/tetrapage_bench_accuracy --scene $(DEMO_DIR)/scene.ply --object $(DEMO_DIR)/object.ply \
	  --steps 2000 --out $(BUILD)/bench-results/accuracy

# Tessellation as a knob of the accuracy trade: a STEP environment and object at a few
# deflections against the oracle over the finest one (docs/BENCHMARKS.md, "Speed against
# accuracy"); deflection.md in $(BUILD)/bench-results/deflection.
bench-deflection: build
	BUILD=$(BUILD) bench/scripts/deflection_series.sh $(BUILD)/bench-results/deflection

format:
	find formats runtime preprocess study tools tests bench -name '*.h' -o -name '*.cpp' -o -name '*.c' | xargs clang-format -i

clean:
	rm -rf $(BUILD) $(BUILD)-asan $(BUILD)-tsan $(FUZZ_BUILD)
