# Fresh machine: `make demo` runs the Hertz benchmark with its plots, `make test` runs the tests.
# Both install what is missing first (Eigen through apt-get, the package with its test, docs and MPI extras).
PYTHON ?= python3
OUT ?= out
LEVELS ?= 7
FRICTION ?= 0.4
PIP = $(PYTHON) -m pip install --disable-pip-version-check -q
# The editable installs compile incrementally in build/ in a folder of their own Python environment
# (a hash of its sys.prefix): two environments installing from this checkout at once never share
# CMake's cache and objects (the wheel tag alone is the same for two venvs of one Python). A plain
# pip install or pip wheel builds in a temporary folder (pyproject.toml sets no build-dir).
ENV_ID := $(shell $(PYTHON) -c "import hashlib, sys; print(hashlib.sha1(sys.prefix.encode()).hexdigest()[:12])" 2>/dev/null || echo default)
BUILD_DIR = build/editable-$(ENV_ID)

.PHONY: setup demo test test-all benchmark sanitize clean docs

setup:
	@if [ ! -f /usr/include/eigen3/Eigen/Core ]; then \
	  echo "installing libeigen3-dev"; \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && apt-get install -y -qq libeigen3-dev; \
	  else sudo apt-get update -qq && sudo apt-get install -y -qq libeigen3-dev; fi; fi
	$(PIP) "scikit-build-core>=0.10" "pybind11>=2.12" numpy
	$(PIP) --no-build-isolation -Cbuild-dir=$(BUILD_DIR) -e ".[test,docs,mpi]"

# table1: the paper's adaptive hierarchy, levels 3 5 7 9 11 (464,670 dofs), both algorithms for the ten
# coefficients in two processes; exit status 3 (runs that did not converge, reported) does not stop the demo.
demo: setup
	mkdir -p $(OUT)
	@date +%s > $(OUT)/.demo_start
	$(PYTHON) -m contactmg hertz --levels $(LEVELS) --friction $(FRICTION) \
	  --json $(OUT)/hertz.json --vtu $(OUT)/hertz.vtu --plot $(OUT)/hertz_stress.png
	$(PYTHON) -m contactmg table1 --json $(OUT)/table1.json --plot $(OUT)/table1.png; \
	  s=$$?; if [ $$s -ne 0 ] && [ $$s -ne 3 ]; then exit $$s; fi
	@echo "wrote $(OUT)/hertz.json $(OUT)/hertz.vtu $(OUT)/hertz_stress.png (Figure 2 middle)" \
	  "$(OUT)/table1.json $(OUT)/table1.png (adaptive Table 1, Figure 1) in $$(( $$(date +%s) - $$(cat $(OUT)/.demo_start) )) s"

test: setup
	$(PYTHON) -m pytest -q

test-all: setup
	$(PYTHON) -m pytest -q -m ""

# The documentation site into site/ (the benchmark pages are generated from benchmarks/results first).
docs: setup
	$(PYTHON) docs/gen_benchmark_pages.py
	$(PYTHON) -m mkdocs build --strict -d site

benchmark: setup
	$(PYTHON) benchmarks/run_all.py

# C++ core under AddressSanitizer and UndefinedBehaviorSanitizer, tests run against it.
sanitize:
	$(PIP) "scikit-build-core>=0.10" "pybind11>=2.12" numpy
	CMAKE_ARGS="-DCONTACTMG_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo" $(PIP) --no-build-isolation \
	  -Cbuild-dir=build/sanitize-$(ENV_ID) -e ".[test]"
	ASAN_OPTIONS=detect_leaks=0 LD_PRELOAD="$$(gcc -print-file-name=libasan.so) $$(gcc -print-file-name=libubsan.so)" \
	  UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 $(PYTHON) -m pytest -q -x tests -k "not notebook"
	$(PIP) --no-build-isolation -Cbuild-dir=$(BUILD_DIR) -e ".[test]"

clean:
	rm -rf build site $(OUT)
