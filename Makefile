# internodes: `make demo` runs the main job, `make test` runs every check.
# Each target installs the Debian packages it needs first (.ci/install-deps.sh).

PYTHON  := /usr/bin/python3
BINARY  := target/release/internodes
LEVELS  ?= 0 1 2
# Cargo features: petsc = the CG + AMG body solver (links the system's PETSc). `make FEATURES=`
# builds and tests without it.
FEATURES ?= petsc

.PHONY: deps build demo picture test validate foreign-meshes outside-check meshes bench clean

deps:
	bash .ci/install-deps.sh

build: deps
	cargo build --release --features "$(FEATURES)"

# Mesh geo/hemisphere_on_block.geo with gmsh and solve the 3D Hertz contact of an elastic
# hemisphere pressed onto an elastic block (INTERNODES, frictionless).
# Open out/demo/solution.xdmf in ParaView (XDMF3 reader); out/demo/summary.json has the contact
# force, the Hertz fit and the iteration history.
demo: build
	$(BINARY) solve geo/hemisphere_on_block.toml --output out/demo

# Unit and integration tests (no gmsh or Python needed), then the quick validation: the
# coarsest level of every suite, same thresholds (report in validation/build/report-quick/).
test: build
	cargo test --release --features "$(FEATURES)"
	$(PYTHON) validation/run.py --quick

# The full validation: every suite at every level; writes validation/report/ (committed).
validate: build
	$(PYTHON) validation/run.py

# The README's picture (docs/demo.png), drawn from the demo's output files.
picture: demo
	$(PYTHON) validation/render_demo.py

# The held-out checks, on meshes made without geo/ (about 40 and 15 minutes; reports in
# validation/report/foreign_meshes.md and validation/report/outside_check.md).
foreign-meshes: build
	$(PYTHON) validation/foreign_meshes.py

outside-check: build
	$(PYTHON) validation/outside_check.py

# Every geo/ script at the refinement levels $(LEVELS), into meshes/.
meshes: deps
	bash geo/mesh_all.sh meshes $(LEVELS)

# Assembly and solve timings against dolfinx (several minutes; report in validation/BENCHMARK.md).
bench: build
	$(PYTHON) validation/benchmark.py --sizes all
	$(PYTHON) validation/contact_benchmark.py --sizes all

clean:
	cargo clean
	rm -rf out meshes validation/build
