# phymul: the two commands of the README, and a few more.
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: all deps deps-demo deps-sanitize configure build test test-asan demo bench format clean

all: build

deps:
	@scripts/install-deps.sh build

deps-demo:
	@scripts/install-deps.sh demo

deps-sanitize:
	@scripts/install-deps.sh sanitize

configure: deps
	@cmake -S . -B $(BUILD) $(CMAKE_FLAGS) > $(BUILD).configure.log 2>&1 || (cat $(BUILD).configure.log; exit 1)

build: configure
	@cmake --build $(BUILD) -j$(JOBS)

test: build
	@cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

# The suite under AddressSanitizer and UndefinedBehaviorSanitizer, assertions on (a separate
# build, with clang: it compiles a sanitized file five times faster than GCC). The same tree
# holds the fuzz targets (make fuzz-build), so that CI compiles the library once.
# SANITIZE_TESTS picks the tests by ctest arguments (CI: -LE 'study|long', all but the studies and the longest tests).
SANITIZE_TESTS ?=
ASAN_DIR = $(BUILD)-asan

asan-configure: deps-sanitize
	@cmake -S . -B $(ASAN_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14 \
		-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DPHYMUL_SANITIZE=ON -DPHYMUL_FUZZ=ON \
		-DPHYMUL_BENCH=OFF > $(ASAN_DIR).configure.log 2>&1 || (cat $(ASAN_DIR).configure.log; exit 1)

test-asan: asan-configure
	@cmake --build $(ASAN_DIR) -j$(JOBS)
	@cd $(ASAN_DIR) && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
		LSAN_OPTIONS=suppressions=$(CURDIR)/scripts/lsan.supp \
		UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
		ctest --output-on-failure -j$(JOBS) $(SANITIZE_TESTS)

demo: build deps-demo
	@scripts/demo.sh $(BUILD)

bench: build
	@scripts/bench.sh $(BUILD)

format:
	@clang-format -i $$(git ls-files '*.cpp' '*.hpp')

clean:
	@rm -rf $(BUILD) $(BUILD).configure.log $(ASAN_DIR) $(ASAN_DIR).configure.log

# Fuzzing (libFuzzer + ASan + UBSan, clang, in the sanitized tree): the scene reader, the
# Truth Cube CSV reader, the VTK, VTK XML (.vtu, .vtp), Gmsh and closed-surface (STL, OBJ,
# PLY) mesh readers, the checkpoint reader, the CamiTK PML/LML readers and the NIfTI label
# image reader (with the surface of small images), each run for FUZZ_SECONDS from a seed
# corpus, as many at once as make's -j; findings are written as build-asan/crash-*.
FUZZ_DIR = $(ASAN_DIR)
FUZZ_SECONDS ?= 60
FUZZ_TARGETS := scene truthcube mesh_vtk mesh_vtkxml mesh_gmsh mesh_surface checkpoint pml nifti

.PHONY: asan-configure fuzz fuzz-build fuzz-corpus $(addprefix fuzz-,$(FUZZ_TARGETS))

fuzz-build: asan-configure
	@cmake --build $(FUZZ_DIR) -j$(JOBS) --target $(patsubst %,%_fuzz,$(FUZZ_TARGETS))

FUZZ_RUN = ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/scripts/lsan.supp \
	UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	./$(1)_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 \
	-print_final_stats=1 corpus/$(1)

fuzz: $(addprefix fuzz-,$(FUZZ_TARGETS))

$(addprefix fuzz-,$(FUZZ_TARGETS)): fuzz-%: fuzz-corpus
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,$*)

fuzz-corpus: fuzz-build
	@for t in $(FUZZ_TARGETS); do mkdir -p $(FUZZ_DIR)/corpus/$$t; done
	@cp examples/*.yaml tests/data/bad_scenes/*.yaml $(FUZZ_DIR)/corpus/scene/
	@cp data/truthcube/uniaxial_positions.csv $(FUZZ_DIR)/corpus/truthcube/
	@cp examples/meshes/*.vtk tests/data/bad_meshes/*.vtk $(FUZZ_DIR)/corpus/mesh_vtk/
	@cp examples/meshes/*.msh tests/data/bad_meshes/*.msh $(FUZZ_DIR)/corpus/mesh_gmsh/
	@cp tests/data/vtkxml/*.vt[up] tests/data/bad_meshes/*.vt[up] $(FUZZ_DIR)/corpus/mesh_vtkxml/
	@cp tests/data/checkpoints/* $(FUZZ_DIR)/corpus/checkpoint/
	@cp tests/data/surfaces/*.stl tests/data/surfaces/*.obj tests/data/surfaces/*.ply \
		tests/data/bad_meshes/*.stl tests/data/bad_meshes/*.obj tests/data/bad_meshes/*.ply \
		$(FUZZ_DIR)/corpus/mesh_surface/
	@cp tests/data/camitk/* tests/data/bad_camitk/*.pml tests/data/bad_camitk/*.lml \
		$(FUZZ_DIR)/corpus/pml/
	@cp tests/data/bad_images/*.nii* tests/data/images/*.nii* $(FUZZ_DIR)/corpus/nifti/
