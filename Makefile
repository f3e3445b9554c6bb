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
# build, with clang: it compiles a sanitized file five times faster than GCC).
# SANITIZE_TESTS picks the tests by ctest arguments (CI: -L unit|cli, every label but study).
SANITIZE_TESTS ?=
test-asan: deps-sanitize
	@cmake -S . -B $(BUILD)-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14 \
		-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DPHYMUL_SANITIZE=ON -DPHYMUL_BENCH=OFF \
		> $(BUILD)-asan.configure.log 2>&1 || (cat $(BUILD)-asan.configure.log; exit 1)
	@cmake --build $(BUILD)-asan -j$(JOBS)
	@cd $(BUILD)-asan && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
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
	@rm -rf $(BUILD) $(BUILD).configure.log $(BUILD)-asan $(BUILD)-asan.configure.log \
		$(FUZZ_DIR) $(FUZZ_DIR).configure.log

# Fuzzing (libFuzzer + ASan + UBSan, clang): the scene reader, the Truth Cube CSV reader, the
# VTK, VTK XML (.vtu, .vtp), Gmsh and closed-surface (STL, OBJ, PLY) mesh readers, the
# checkpoint reader, the CamiTK PML/LML readers and the NIfTI label image reader (with the
# surface of small images), each run for FUZZ_SECONDS from a seed
# corpus; findings are written as build-fuzz/crash-*.
FUZZ_DIR ?= build-fuzz
FUZZ_SECONDS ?= 60

.PHONY: fuzz fuzz-build

fuzz-build: deps-sanitize
	@cmake -S . -B $(FUZZ_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14 \
		-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DPHYMUL_SANITIZE=ON -DPHYMUL_FUZZ=ON \
		-DPHYMUL_BENCH=OFF > $(FUZZ_DIR).configure.log 2>&1 || (cat $(FUZZ_DIR).configure.log; exit 1)
	@cmake --build $(FUZZ_DIR) -j$(JOBS) --target $(patsubst %,%_fuzz,$(FUZZ_TARGETS))

FUZZ_TARGETS := scene truthcube mesh_vtk mesh_vtkxml mesh_gmsh mesh_surface checkpoint pml nifti
FUZZ_RUN = ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions=$(CURDIR)/scripts/lsan.supp \
	UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	./$(1)_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 \
	-print_final_stats=1 corpus/$(1)

fuzz: fuzz-build
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
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,scene)
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,truthcube)
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,mesh_vtk)
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,mesh_vtkxml)
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,mesh_gmsh)
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,mesh_surface)
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,checkpoint)
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,pml)
	cd $(FUZZ_DIR) && $(call FUZZ_RUN,nifti)
