# internodes: `make demo` runs the main job, `make test` runs every check.
# Each target installs the Debian packages it needs first (.ci/install-deps.sh).

PYTHON  := /usr/bin/python3
BINARY  := target/release/internodes
# The Python module is installed into this virtual environment, which sees Debian's numpy, gmsh,
# h5py and matplotlib (--system-site-packages).
VENV    := build/venv
LEVELS  ?= 0 1 2
# Cargo features: petsc = the CG + AMG body solver (links the system's PETSc). `make FEATURES=`
# builds and tests without it.
FEATURES ?= petsc

.PHONY: deps build python akantu demo picture test validate foreign-meshes outside-check meshes bench clean

deps:
	bash .ci/install-deps.sh

build: deps
	cargo build --release --features "$(FEATURES)"

# The Python module (python/): `import internodes` in $(VENV), built from this repository by
# maturin, with mypy for its stub test. Use it with $(VENV)/bin/python, or install it anywhere
# with `pip install ./python`.
python: build
	test -x $(VENV)/bin/python || $(PYTHON) -m venv --system-site-packages $(VENV)
	$(VENV)/bin/pip install --quiet "maturin>=1.5,<2" mypy
	@echo "make python: building the Rust module with maturin (release; several minutes on 2 cores the first time, pip prints nothing meanwhile)"
	MATURIN_PEP517_ARGS="$(if $(findstring petsc,$(FEATURES)),,--no-default-features)" \
	    $(VENV)/bin/pip install --quiet ./python

# Mesh geo/hemisphere_on_block.geo with gmsh and solve the 3D Hertz contact of an elastic
# hemisphere pressed onto an elastic block (INTERNODES, frictionless).
# Open out/demo/solution.xdmf in ParaView (XDMF3 reader); out/demo/summary.json has the contact
# force, the Hertz fit and the iteration history.
demo: build
	$(BINARY) solve geo/hemisphere_on_block.toml --output out/demo

# Unit and integration tests (tests/mpi.rs runs the solver on 2 and 3 MPI ranks with mpirun),
# the API docs without a broken or private link, the Python module's tests and examples, then
# the quick validation: the coarsest level of every suite, same thresholds (report in
# validation/build/report-quick/).
test: build python
	cargo test --release --features "$(FEATURES)"
	RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --features "$(FEATURES)"
	$(VENV)/bin/python -m pytest python/tests
	$(PYTHON) validation/run.py --quick

# The full validation: every suite at every level; writes validation/report/ (committed).
validate: build akantu
	$(PYTHON) validation/run.py

# Akantu (the penalty contact the validation compares ours with), from PyPI into its own virtual
# environment: the validation's only, never the solver's.
akantu:
	test -x build/akantu/bin/python || $(PYTHON) -m venv build/akantu
	build/akantu/bin/pip install --quiet "akantu==5.0.7.post1"

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
	rm -rf out meshes validation/build build
