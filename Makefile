# Two commands from a fresh clone:
#   make demo   sets everything up and runs the main job on the paper's example
#   make test   sets everything up and runs every test
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
OUT    := out

.PHONY: setup system-deps demo test test-slow clean

# graphviz's `dot` lays out PNML drawings and renders figures: from Debian's
# packages where missing (machines here run as root).
system-deps:
	@command -v dot >/dev/null 2>&1 || { \
	  echo "installing graphviz (dot) with apt-get"; \
	  (apt-get update -qq && apt-get install -y -qq graphviz >/dev/null) \
	  || echo "warning: could not install graphviz; tests that need dot will say so"; }

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

setup: system-deps $(STAMP)

demo: setup
	@mkdir -p $(OUT)
	$(PY) examples/handbuilt_primitive.py $(OUT)/primitive.pnml
	$(BIN)/mcl2pnml validate $(OUT)/primitive.pnml
	@echo
	@echo "outputs:"
	@echo "  $(OUT)/primitive.pnml  the vehicle primitive (Fig. 1) built with the net core, as PNML"

test: setup
	$(PY) -m pytest

test-slow: setup
	$(PY) -m pytest -m slow

clean:
	rm -rf $(VENV) $(OUT) paper_repro/out .pytest_cache .hypothesis *.egg-info
