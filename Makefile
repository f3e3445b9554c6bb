# phymul: the two commands of the README, and a few more.
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: all deps deps-demo configure build test test-asan demo bench format clean

all: build

deps:
	@scripts/install-deps.sh build

deps-demo:
	@scripts/install-deps.sh demo

configure: deps
	@cmake -S . -B $(BUILD) $(CMAKE_FLAGS) > $(BUILD).configure.log 2>&1 || (cat $(BUILD).configure.log; exit 1)

build: configure
	@cmake --build $(BUILD) -j$(JOBS)

test: build
	@cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# The whole suite under AddressSanitizer and UndefinedBehaviorSanitizer (a separate build).
test-asan: deps
	@cmake -S . -B $(BUILD)-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPHYMUL_SANITIZE=ON \
		> $(BUILD)-asan.configure.log 2>&1 || (cat $(BUILD)-asan.configure.log; exit 1)
	@cmake --build $(BUILD)-asan -j$(JOBS)
	@cd $(BUILD)-asan && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
		UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j$(JOBS)

demo: build deps-demo
	@scripts/demo.sh $(BUILD)

bench: build
	@scripts/bench.sh $(BUILD)

format:
	@clang-format -i $$(git ls-files '*.cpp' '*.hpp')

clean:
	@rm -rf $(BUILD) $(BUILD).configure.log $(BUILD)-asan $(BUILD)-asan.configure.log

# Fuzzing (libFuzzer + ASan + UBSan, clang): the scene reader and the Truth Cube CSV reader,
# each run for FUZZ_SECONDS from a seed corpus; findings are written as build-fuzz/crash-*.
FUZZ_DIR ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_CXX ?= clang++-14
FUZZ_FLAGS := -std=c++20 -O1 -g -fno-omit-frame-pointer -Iinclude -Isrc -I/usr/include/eigen3
FUZZ_SANITIZE := -fsanitize=address,undefined
FUZZ_LIBS := -lyaml-cpp -lfmt
FUZZ_LIB_SRCS := $(wildcard src/io/scene.cpp src/io/scene_reader.cpp src/io/units.cpp \
	src/io/parameter_table.cpp src/mesh/*.cpp src/validation/truthcube.cpp)
FUZZ_LIB_OBJS := $(patsubst src/%.cpp,$(FUZZ_DIR)/obj/%.o,$(FUZZ_LIB_SRCS))

.PHONY: fuzz fuzz-build
.SECONDARY: $(FUZZ_LIB_OBJS)

$(FUZZ_DIR)/obj/%.o: src/%.cpp
	@mkdir -p $(dir $@)
	$(FUZZ_CXX) $(FUZZ_FLAGS) $(FUZZ_SANITIZE) -fsanitize=fuzzer-no-link -c $< -o $@

$(FUZZ_DIR)/%: fuzz/%.cpp $(FUZZ_LIB_OBJS)
	@mkdir -p $(dir $@)
	$(FUZZ_CXX) $(FUZZ_FLAGS) $(FUZZ_SANITIZE) -fsanitize=fuzzer $< $(FUZZ_LIB_OBJS) \
		$(FUZZ_LIBS) -o $@

fuzz-build: $(FUZZ_DIR)/scene_fuzz $(FUZZ_DIR)/truthcube_fuzz

fuzz: fuzz-build
	@mkdir -p $(FUZZ_DIR)/corpus/scene $(FUZZ_DIR)/corpus/truthcube
	@cp examples/*.yaml tests/data/bad_scenes/*.yaml $(FUZZ_DIR)/corpus/scene/
	@cp data/truthcube/uniaxial_positions.csv $(FUZZ_DIR)/corpus/truthcube/
	cd $(FUZZ_DIR) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
		./scene_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 \
		-print_final_stats=1 corpus/scene
	cd $(FUZZ_DIR) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
		./truthcube_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 \
		-print_final_stats=1 corpus/truthcube
