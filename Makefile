# tmpnav: two commands set everything up on a fresh machine (see README):
#   make demo   creates .venv, installs tmpnav, checks Java, plans the paper's corridor into out/
#   make test   creates .venv if needed and runs the whole test suite

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test bench bench-full lint regression-update clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test,lint]'
	touch $(STAMP)

demo: $(STAMP)
	@$(BIN)/tmpnav doctor
	$(BIN)/tmpnav validate configs/corridor.yaml
	$(BIN)/tmpnav show configs/corridor.yaml -o out/world.png
	$(BIN)/tmpnav plan configs/corridor.yaml -o out/

# pytest's exit code 5 means "no tests collected": not a failure of the suite.
test: $(STAMP)
	$(BIN)/pytest -q; rc=$$?; if [ $$rc -eq 5 ]; then exit 0; fi; exit $$rc

bench: $(STAMP)
	$(BIN)/python benchmarks/run.py --quick

bench-full: $(STAMP)
	$(BIN)/python benchmarks/run.py

lint: $(STAMP)
	$(BIN)/ruff check tmpnav tests benchmarks
	$(BIN)/mypy tmpnav

regression-update: $(STAMP)
	$(BIN)/python -m tmpnav.bench.regression --update

clean:
	rm -rf out .pytest_cache .mypy_cache .ruff_cache

# Property-based fuzzing of the inputs through the real CLI, about ten minutes of random
# examples (CI runs a fixed smoke set in `make test`); record results in tests/fuzz/RESULTS.md.
FUZZ_SCALE ?= 2
.PHONY: fuzz
fuzz: $(STAMP)
	TMPNAV_FUZZ_EXAMPLES=$(FUZZ_SCALE) $(BIN)/pytest -q tests/fuzz -p no:cacheprovider --durations=5
