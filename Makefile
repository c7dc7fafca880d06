# tlm: two commands work on a fresh machine with Python 3.11 and make.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
OUT    ?= demo-out

.PHONY: demo test lint bench clean

# A .venv made by another Python (an earlier try with the wrong one, or a Python since
# removed) is rebuilt with $(PYTHON) instead of being reused.
PY_WANT := $(shell $(PYTHON) -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)
PY_HAVE := $(shell $(PY) -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)
ifneq ($(PY_WANT),)
ifneq ($(wildcard $(VENV)),)
ifneq ($(PY_HAVE),$(PY_WANT))
$(info $(VENV) runs Python $(or $(PY_HAVE),(none: broken)), not $(PY_WANT) ($(PYTHON)): rebuilding it)
$(shell rm -rf $(VENV))
endif
endif
endif

$(VENV)/bin/activate:
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "need $(PYTHON) on PATH (or run: make PYTHON=python3 ...)"; exit 2; }
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip

$(VENV)/.installed: $(VENV)/bin/activate pyproject.toml
	$(PY) -m pip install -q -e .
	touch $@

$(VENV)/.installed-test: $(VENV)/bin/activate pyproject.toml
	$(PY) -m pip install -q -e '.[test]'
	touch $(VENV)/.installed $@

demo: $(VENV)/.installed
	$(VENV)/bin/tlm demo --out $(OUT)

test: $(VENV)/.installed-test
	$(PY) -m pytest -n 2 -q

lint: $(VENV)/.installed-test
	$(VENV)/bin/ruff check tlm_sim tlm_process tests benchmarks tools

bench: $(VENV)/.installed
	$(PY) benchmarks/bench_fly.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache build *.egg-info
