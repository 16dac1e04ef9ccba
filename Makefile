# sgbem — pipelines from gmsh geometry to results.  `make` shows the menu.

SHELL := /bin/bash
.DELETE_ON_ERROR:
.DEFAULT_GOAL := help
.PHONY: help setup build mesh test test-long lint demo examples accuracy bench report clean view man

CARGO   ?= cargo
GMSH    ?= gmsh
VENV    := .venv
PY      := $(VENV)/bin/python
SGBEM   := target/release/sgbem
# Extra gmsh options for every mesh, e.g. make mesh MESH_OPTS="-setnumber h 2"
MESH_OPTS ?=
SUDO    := $(shell [ "$$(id -u)" -eq 0 ] || echo sudo)
APT_PACKAGES := libhdf5-dev pkg-config gmsh libosmesa6
PY_PACKAGES  := meshio pyvista h5py matplotlib pandas pytest jsonschema snakemake

GEO    := $(wildcard geo/*.geo)
MESHES := $(patsubst geo/%.geo,out/mesh/%.msh,$(GEO))
SCENES := $(wildcard pipelines/*.toml)
RESULTS := $(patsubst pipelines/%.toml,out/%/summary.json,$(SCENES))

help:
	@echo "sgbem — make targets"
	@echo "  make demo      set up, build, mesh and check the paper's clamped-beam example"
	@echo "  make test      set up, then run every test (what CI runs)"
	@echo "  make test-long the tests too long for CI (minutes each), marked #[ignore = \"long ...\"]"
	@echo "  make setup     install what is missing: apt ($(APT_PACKAGES)), $(VENV) ($(PY_PACKAGES)) and the package sgbem (python/)"
	@echo "  make build     cargo build --release"
	@echo "  make lint      cargo fmt --check, clippy and rustdoc with warnings denied (part of make test)"
	@echo "  make mesh      mesh geo/*.geo into out/mesh/*.msh (MESH_OPTS=\"-setnumber h 2\")"
	@echo "  make examples  run every pipeline"
	@echo "  make vault     the paper's vault (example 3) for five cohesions, tables in out/vault/"
	@echo "  make sweep     a sweep file in Snakemake, a job per point (SWEEP=pipelines/sweeps/wall_friction.toml)"
	@echo "  make arch-min  the minimum thickness of a semicircular arch by bisection (out/arch_min/)"
	@echo "  make accuracy  refinement studies: error and time"
	@echo "  make bench     per-stage benchmarks"
	@echo "  make report    refresh the committed pictures (docs/img) and docs/results.md"
	@echo "  make man       the manual page, target/sgbem.1 (man -l target/sgbem.1)"
	@echo "  make view NAME=clamped_beam_joint   render a run in ParaView (off-screen)"
	@echo "  make clean     remove out/ (meshes and results; not the build: cargo clean)"

setup:
	@missing=""; for p in $(APT_PACKAGES); do \
	  dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "setup: installing$$missing"; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $$missing >/dev/null; \
	fi
	@test -x $(PY) || python3 -m venv $(VENV)
	@$(PY) -c "import meshio, pyvista, h5py, matplotlib, pandas, pytest, jsonschema, snakemake" 2>/dev/null || \
	  { echo "setup: installing $(PY_PACKAGES) into $(VENV)"; \
	    $(PY) -m pip install -q --disable-pip-version-check $(PY_PACKAGES); }
	@# The Python package sgbem (python/), editable: the venv follows the working tree.
	@$(PY) -c "import sgbem, pathlib, sys; \
	  sys.exit(pathlib.Path(sgbem.__file__).resolve().parent != pathlib.Path('python/sgbem').resolve())" \
	  2>/dev/null || { echo "setup: installing the Python package sgbem (python/) into $(VENV)"; \
	    $(PY) -m pip install -q --disable-pip-version-check -e python; }

build:
	$(CARGO) build --release

# Formatting, clippy's lints and the documentation's links, warnings denied (make test runs it).
# --release: the proc macros and build scripts clippy compiles are then the ones the release
# build and tests use (compiled once, not once per profile): a cold lint 199 s, not 480 s.
lint:
	$(CARGO) fmt --check
	$(CARGO) clippy --release --all-targets -- -D warnings
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --release --no-deps

mesh: $(MESHES)

# The meshes depend on MESH_OPTS through a stamp file rewritten only when the options change.
MESH_STAMP := out/mesh/.mesh_opts
$(MESH_STAMP): FORCE
	@mkdir -p $(@D)
	@echo '$(MESH_OPTS)' | cmp -s - $@ || echo '$(MESH_OPTS)' > $@
.PHONY: FORCE
FORCE:

out/mesh/%.msh: geo/%.geo $(MESH_STAMP)
	@mkdir -p $(@D)
	$(GMSH) -2 -format msh41 $(MESH_OPTS) $< -o $@.tmp.msh > $@.log
	@mv $@.tmp.msh $@

demo: setup build mesh
	$(SGBEM) check pipelines/clamped_beam_joint.toml
	$(SGBEM) run pipelines/clamped_beam_joint.toml --out out/clamped_beam_joint
	@echo
	@echo "demo: results of the paper's example 2 in out/clamped_beam_joint/:"
	@echo "  summary.json, archive.h5 (sgbem inspect), interfaces/joint.csv, sections/a-a.csv,"
	@echo "  vtk/states.pvd (ParaView: Warp By Vector on displacement, play the iterations)"

test: setup mesh lint
	CARGO=$(CARGO) bash tests/run_binaries.sh
	$(CARGO) build --release
	@# The Python package (python/) against real runs of the built sgbem.
	@# (with ParaView installed also view.py and the VTK series in pvpython; skipped otherwise)
	$(PY) -m pytest -q -rs python/tests
	$(PY) pipelines/check_meshes.py $(SGBEM) $(MESHES)
	@# out/test/ is this target's own scratch folder: its runs start afresh.
	rm -rf out/test
	$(SGBEM) run pipelines/clamped_beam_joint.toml --out out/test/clamped_beam_joint --quiet
	$(PY) pipelines/check_outputs.py out/test/clamped_beam_joint
	@# A multi-body, multi-step, frictional run: history, VTK and archive agree at every step.
	$(SGBEM) run pipelines/cattaneo_mindlin.toml --out out/test/cattaneo_mindlin --quiet
	$(PY) pipelines/check_outputs.py out/test/cattaneo_mindlin
	$(SGBEM) run pipelines/vault_c0.toml --out out/test/vault_c0 --quiet
	$(PY) pipelines/check_outputs.py out/test/vault_c0
	@# A running-bond wall: 22 bodies, T-junctions, friction, compact archived states (the
	@# evolutive path: the full rows, the default here, keep one state per load step).
	$(SGBEM) run pipelines/wall_running_bond.toml --method lcp --set mesh.courses=4 --set mesh.bricks=5 --out out/test/wall_running_bond --quiet
	$(PY) pipelines/check_outputs.py out/test/wall_running_bond
	@# Output requests: the state at the end of each load step, compressed VTK; every 5th
	@# iteration with a selection of the VTK arrays.
	$(SGBEM) run pipelines/wall_running_bond.toml --set mesh.courses=4 --set mesh.bricks=5 --set 'output.history="steps"' --set 'output.vtk="compressed"' --out out/test/wall_steps --quiet
	$(PY) pipelines/check_outputs.py out/test/wall_steps
	$(SGBEM) run pipelines/clamped_beam_joint.toml --set output.every=5 --set 'output.vtk_fields=["displacement","contact_status","stress","sxx","syy","szz","sxy"]' --out out/test/beam_every --quiet
	$(PY) pipelines/check_outputs.py out/test/beam_every
	@# Contact from the drawing: 220 stones drawn each on its own, joints found by [contact].
	$(SGBEM) run pipelines/stone_wall.toml --out out/test/stone_wall --quiet
	$(PY) pipelines/check_outputs.py out/test/stone_wall
	@# ParaView itself (opportunistic: not installed by `make setup`, it adds minutes).
	@if command -v pvpython >/dev/null && command -v xvfb-run >/dev/null; then \
	  for run in clamped_beam_joint wall_running_bond wall_steps beam_every; do \
	    echo "xvfb-run -a pvpython pipelines/check_pvd_paraview.py out/test/$$run"; \
	    xvfb-run -a pvpython pipelines/check_pvd_paraview.py out/test/$$run || exit 1; \
	  done; \
	else \
	  echo "test: ParaView check SKIPPED: no pvpython or xvfb-run (apt-get install -y paraview xvfb)"; \
	fi

# Tests too long for CI's 30 minutes (marked `#[ignore = "long ..."]`): run before a change
# to the sparse solver's friction iteration or to [contact]'s detection.
test-long: setup mesh
	$(CARGO) test --release --test friction -- --ignored --exact stone_wall_with_coulomb_joints_stands_under_its_weight
	$(CARGO) test --release --test full_rows -- --ignored --exact the_stone_wall_with_coulomb_joints_stands_where_a_stone_was_left_free
	$(CARGO) test --release --test full_rows -- --ignored --exact the_stone_wall_with_coulomb_joints_stands_at_an_eighth_of_g

examples: build mesh $(RESULTS)

# Examples that show a mechanism end with exit 3 by design (every output written).
MECHANISM_EXAMPLES := incline_block_slides

out/%/summary.json: pipelines/%.toml $(MESHES) | build
	@if echo " $(MECHANISM_EXAMPLES) " | grep -q " $* "; then \
	  echo "$(SGBEM) run $< --out out/$* --quiet   (a mechanism: exit 3 expected)"; \
	  $(SGBEM) run $< --out out/$* --quiet; code=$$?; \
	  if [ $$code -ne 3 ]; then echo "examples: $* should end with exit 3, got $$code"; exit 1; fi; \
	else \
	  echo "$(SGBEM) run $< --out out/$* --quiet"; \
	  $(SGBEM) run $< --out out/$* --quiet; \
	fi

# The paper's example 3: the vault on two piers for cohesion 0.4 ... 0 MPa (the sweep file
# pipelines/sweeps/vault.toml: one folder per cohesion in out/vault/sweep/, with sweep.csv),
# then the tables beside the paper's Tables 3 and 4 (out/vault/table3.md, table4.md).
.PHONY: vault
JOBS ?= 2

vault: build out/mesh/vault.msh
	$(SGBEM) sweep --file pipelines/sweeps/vault.toml --jobs $(JOBS)
	python3 pipelines/vault_table.py out

# A sweep file (pipelines/sweeps/*.toml: scene, --set values, folder) through the generic
# Snakemake workflow pipelines/Snakefile: one job per point (JOBS at a time), then the table.
.PHONY: sweep
SWEEP ?= pipelines/sweeps/wall_friction.toml
sweep: setup build
	$(VENV)/bin/snakemake -s pipelines/Snakefile --cores $(JOBS) --config sweep=$(SWEEP) sgbem=$(SGBEM)

# The minimum thickness of a semicircular arch (40 voussoirs, friction mu = 1) by bisection
# on t/R between a ring that stands and one that collapses: out/arch_min/result.md.
.PHONY: arch-min
arch-min: setup build
	$(PY) pipelines/arch_min_thickness.py $(SGBEM) --out out/arch_min

bench:
	$(CARGO) bench --bench stages
	$(CARGO) bench --bench contact
	$(CARGO) bench --bench masonry
	$(CARGO) bench --bench detect

# Refinement levels x quadrature presets of the closed-form benchmarks and of the paper's
# examples 1 and 2: error (or detached length) against run time, in out/accuracy/
# (accuracy.csv, accuracy.md, accuracy_*.png); about 6 minutes on 2 cores.
accuracy: build mesh
	$(PY) pipelines/accuracy.py

# Pictures of every run (docs/img/<run>_*.png: strained shapes, detachment along the
# interfaces per iteration, sections, the paper's Figs. 5 and 6; thrust_arch.png and
# thrust_wall.png: the thrust lines of out/arch and out/wall) and docs/results.md (headline
# figures beside the paper's Tables 1-4). A run folder missing under out/ is skipped.
man: build
	./target/release/sgbem man > target/sgbem.1
	@echo "man: wrote target/sgbem.1 (read it with: man -l target/sgbem.1)"

report: setup
	@$(MAKE) --no-print-directory -k examples || \
	  echo "report: some runs failed (see above): their folders are skipped or show the previous run"
	@mkdir -p docs/img
	$(PY) pipelines/report.py $(dir $(RESULTS)) --out docs/img
	$(PY) pipelines/results.py out --img docs/img --md docs/results.md
	$(PY) pipelines/friction_plots.py out docs/img
	$(PY) pipelines/thrust_plots.py out docs/img
	@if [ -f out/accuracy/accuracy_benchmarks.png ]; then \
	  cp out/accuracy/accuracy_benchmarks.png docs/img/ && echo "report: docs/img/accuracy_benchmarks.png from out/accuracy/"; \
	else echo "report: no out/accuracy/ (make accuracy): docs/img/accuracy_benchmarks.png left as it is"; fi

# A run's final state rendered off-screen by ParaView (pvpython under xvfb-run): strained
# shape (warp factor: 5 % of the model size over the largest displacement) coloured by von
# Mises where the run has an interior field, into docs/img/NAME_paraview.png (the README's
# screenshots: `make view` is the way to refresh them), and the same view as a ParaView
# state, out/NAME/vtk/view.pvsm. Runs the scene first if out/NAME/ has no results.
NAME ?= clamped_beam_joint
view: out/$(NAME)/summary.json
	@command -v pvpython >/dev/null && command -v xvfb-run >/dev/null || \
	  { echo "view: needs ParaView: apt-get install -y paraview xvfb"; exit 2; }
	@mkdir -p docs/img
	xvfb-run -a pvpython pipelines/view.py out/$(NAME) docs/img/$(NAME)_paraview.png

clean:
	rm -rf out
