# Two entry points, each of which sets everything up from a bare Python >= 3.11:
#   make demo   certify and verify a model file, then certify the paper's gain set
#   make test   run the whole test suite (what CI runs)
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test

$(STAMP): pyproject.toml
	$(PYTHON) -c 'import sys; sys.exit("lyapcheck needs Python >= 3.11") if sys.version_info < (3, 11) else None'
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	@# any closed loop: a model file, certified with every class, then re-checked without a solver
	$(BIN)/lyapcheck certify examples/models/damped-oscillator.toml --out .venv/demo-certificate.json
	$(BIN)/lyapcheck verify .venv/demo-certificate.json
	@# the worked example: the paper's gain set (exit code 1 means "ran correctly, answer negative":
	@# the demo still succeeds); `lyapcheck derive` prints the paper's claims ledger
	$(BIN)/lyapcheck certify examples/paper.toml; test $$? -le 1

test: $(STAMP)
	@# pytest exits 5 when it collects no test: that is a broken suite, not a pass
	$(BIN)/python -m pytest; rc=$$?; if [ $$rc -eq 5 ]; then echo "no tests were collected" >&2; fi; exit $$rc
