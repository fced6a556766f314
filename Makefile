# Two entry points: `make demo` (set up, plan on the bundled map) and `make test`.
PYTHON ?= python3
VENV ?= .venv
# torch is pinned to a CPU build ("+cpu"), so a fresh install never pulls a multi-GB CUDA
# wheel: pip takes it from a local wheel directory or index when one holds it; PyPI has no
# "+cpu" builds, so elsewhere the first attempt fails at once and the CPU index is used.
TORCH_SPEC ?= torch==2.13.0+cpu
TORCH_CPU_INDEX ?= https://download.pytorch.org/whl/cpu
EXTRAS ?= geo,ros,distributed,test
OUT ?= out

.PHONY: setup demo test bench docs clean

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install -q --upgrade pip
	$(VENV)/bin/python -m pip install -q "$(TORCH_SPEC)" || \
	  $(VENV)/bin/python -m pip install -q "$(TORCH_SPEC)" --index-url $(TORCH_CPU_INDEX)
	$(VENV)/bin/python -m pip install -q -e '.[$(EXTRAS)]'
	touch $@

setup: $(VENV)/.installed

demo: $(VENV)/.installed
	$(VENV)/bin/terrawatt demo --out $(OUT)

test: $(VENV)/.installed
	$(VENV)/bin/python -m pytest -q

bench: $(VENV)/.installed
	$(VENV)/bin/python benchmarks/plan_bench.py --out $(OUT)/plan_bench.json

# the API reference from the docstrings (mkdocs.yml), warnings as errors, into $(OUT)/site
$(VENV)/.docs-installed: $(VENV)/.installed pyproject.toml
	$(VENV)/bin/python -m pip install -q -e '.[docs]'
	touch $@

docs: $(VENV)/.docs-installed
	$(VENV)/bin/mkdocs build --strict --site-dir $(OUT)/site

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache
