# Two commands from a fresh clone:
#   make demo   sets everything up and runs the main job on the paper's example
#   make test   sets everything up and runs every test
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-stamp
OUT    := out
# The official PNML grammar (pnml.org's, not ours to ship) where a checkout keeps it, beside
# itself: `validate` never looks for it, so the demo passes it where it is there.
GRAMMAR := ../shared/pnml-grammar

.PHONY: setup system-deps demo test test-slow bench clean

# graphviz's `dot` lays out PNML drawings and renders figures; Chromium plays the
# token game page of `mcl2pnml show` in the browser tests. Both from Debian's
# packages where missing (machines here run as root). GLPK lets TAPAAL's verifypn, one of
# the peer tools the external-corpus tests compare us with, start.
# A C compiler builds the exploration loops (analysis/statespace/loops/_native.c) at install;
# without one mcl2pnml installs all the same and explores with numpy and Python. Java 17 runs
# the PNML readers of the editors WoPeD and PIPE, which the tests hold our files to.
APT_PACKAGES := $(if $(shell command -v dot),,graphviz) $(if $(shell command -v chromium),,chromium) \
                $(if $(shell /sbin/ldconfig -p 2>/dev/null | grep libglpk.so.40),,libglpk40) \
                $(if $(shell command -v cc),,gcc) \
                $(if $(shell command -v java),,openjdk-17-jre-headless)

system-deps:
	@if [ -n "$(strip $(APT_PACKAGES))" ]; then \
	  echo "installing$(APT_PACKAGES) with apt-get"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
	     $(APT_PACKAGES) >/dev/null) \
	  || echo "warning: could not install$(APT_PACKAGES); the tests that need them will say so"; \
	fi

$(STAMP): pyproject.toml analysis/statespace/loops/_native.c
	$(PYTHON) -m venv $(VENV)
	@# uv installs the dependencies in a few seconds where pip takes a minute and more
	@# (pip resolves one by one and compiles every module to bytecode, one at a time; the
	@# modules are compiled below, on every core). Where uv cannot be had or fails, pip
	@# does the same install.
	$(PY) -m pip install --quiet uv || echo "warning: could not install uv; installing with pip"
	@# Storm checks the exact odds in the tests; where its wheel cannot be had, they skip.
	@# One install with it (one resolution, one build of the C loops), without it on failure
	install() { { [ -x $(BIN)/uv ] && $(BIN)/uv pip install --quiet --python $(PY) "$$@"; } \
	            || $(PY) -m pip install --quiet "$$@"; }; \
	install -e '.[test,mavlink,storm]' \
	  || { echo "warning: could not install stormpy; the tests that compare the odds with Storm's will say so"; \
	       install -e '.[test,mavlink]'; }
	@# Byte-compiled once, on every core: otherwise each of the tests' workers, and each
	@# command a test starts, compiles the same libraries before the first has written them
	$(PY) -m compileall -q -j 0 "$$($(PY) -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')" \
	  mcl2pnml analysis templates >/dev/null || echo "warning: could not byte-compile; the tests will"
	touch $(STAMP)

setup: system-deps $(STAMP)

demo: setup
	@mkdir -p $(OUT)
	$(BIN)/mcl2pnml template --list
	$(BIN)/mcl2pnml template task -o $(OUT)/task.pnml
	@# our schema always; the official grammar as well where it is beside the checkout
	$(if $(wildcard $(GRAMMAR)/ptnet.pntd),,@echo "no official PNML grammar at $(GRAMMAR):" \
	  "validating with our schema alone (--grammar DIR adds it)")
	$(BIN)/mcl2pnml validate $(OUT)/task.pnml \
	  $(if $(wildcard $(GRAMMAR)/ptnet.pntd),--grammar $(GRAMMAR))
	$(BIN)/mcl2pnml analyze $(OUT)/task.pnml
	$(PY) -m paper_repro
	$(BIN)/mcl2pnml functional examples/sauce.mcl
	$(BIN)/mcl2pnml compile examples/sauce.mcl -o $(OUT)/sauce.pnml
	$(BIN)/mcl2pnml compile examples/sauce.mcl --format svg -o $(OUT)/sauce.svg
	$(BIN)/mcl2pnml analyze $(OUT)/sauce.pnml --state-space
	$(BIN)/mcl2pnml run examples/sauce.mcl --log $(OUT)/sauce-run.jsonl
	$(BIN)/mcl2pnml show examples/sauce.mcl --run $(OUT)/sauce-run.jsonl -o $(OUT)/sauce.html
	@# every example on the simulator (in the world beside it), with both engines: same --json
	@echo; echo "every example on the simulator, both engines:"
	@for mission in examples/*.mcl; do \
	  for engine in petri reference; do \
	    $(BIN)/mcl2pnml run $$mission --engine $$engine --json > $(OUT)/run-$$engine.json \
	      2> $(OUT)/run-$$engine.err; \
	    status=$$?; [ $$status -le 1 ] || { cat $(OUT)/run-$$engine.err; \
	      echo "  $$mission: $$engine exited $$status"; exit 1; }; \
	  done; \
	  cmp -s $(OUT)/run-petri.json $(OUT)/run-reference.json \
	    || { echo "  $$mission: the engines disagree ($(OUT)/run-*.json)"; exit 1; }; \
	  $(PY) -c 'import json, sys; r = json.load(open(sys.argv[2])); \
	    print("  %-28s %-5s at t=%g s, %d entries, engines agree" \
	          % (sys.argv[1], r["outcome"], r["time"], len(r["trace"])))' \
	    $$mission $(OUT)/run-petri.json; \
	done
	@echo
	@echo "outputs:"
	@echo "  $(OUT)/task.pnml                 the task of Fig. 2 with its primitive, as PNML"
	@echo "  $(OUT)/sauce.pnml, sauce.svg     the paper's mission (Algorithm 1) compiled to one net"
	@echo "  $(OUT)/sauce.html                the token game on it, with the run above: open it in a browser"
	@echo "  paper_repro/out/report.md        equations 1-26: the paper vs what the analysis computes"
	@echo "  paper_repro/out/report.json      the same, for tools"
	@echo "  paper_repro/out/fig1-4.svg/.png  Figs. 1 to 4 redrawn from the templates"
	@echo "  paper_repro/out/fig5.png         Fig. 5: the mission on the simulated AUV, with and without the cross"

# the tests are spread over two workers more than the cores (up to four: each worker
# loads a browser), since a third of their time is spent waiting on peer
# tools, the browser and the autopilot (on 2 cores: 5:35 with 4 workers, 5:57 with 3;
# 5:22 with 6, where tests that time a wait fail under the load);
# a single file runs in one process with `$(PY) -m pytest tests/GROUP/FILE.py`
# --dist worksteal: a worker that runs out takes tests queued on the others, so that the
# run does not end on one worker's tail of long tests
TEST_WORKERS := -n $(shell n=$$(nproc 2>/dev/null || echo 1); echo $$(( n < 2 ? n + 2 : 4 ))) \
                --dist worksteal
# compiled modules are kept (__pycache__, ignored by git) even where the environment
# says not to: otherwise every worker and every Python process the tests start
# compiles the package and rewrites the tests' assertions anew; the fifteen slowest
# tests are listed at the end, so that one growing slower is seen before the suite is
PYTEST := env -u PYTHONDONTWRITEBYTECODE $(PY) -m pytest --durations=15

test: setup
	$(PYTEST) $(TEST_WORKERS)

# every test, the slow ones too, each drawing its whole sample (tests/support/sampling.py)
test-slow: setup
	MCL2PNML_TEST_THOROUGH=1 $(PYTEST) $(TEST_WORKERS) -m ''

bench: setup
	$(PY) -m bench.suite

clean:
	rm -rf $(VENV) $(OUT) paper_repro/out .pytest_cache .hypothesis *.egg-info
