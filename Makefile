# One-command entry points. Both create ./.venv on a fresh machine (only Python 3.11 + pip needed).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup demo test bench fig3 clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	# --no-compile: Python writes the bytecode of what is imported at its first import, instead of pip
	# compiling every module of every package (35 of pip's 61 s here: matplotlib, scipy, dask...)
	$(BIN)/pip install --quiet --no-compile -e '.[test,viewer,batch,bench]'
	@echo "compiling polyfold's numba kernels into their cache, make's kernels ahead of time (with the C compiler) and its modules to bytecode (a minute or two, once, on two cores), so no run waits for them"
	$(BIN)/polyfold warm-up
	touch $(STAMP)

setup: $(STAMP)

demo: $(STAMP)
	$(BIN)/polyfold info examples/bunny-128.obj
	$(BIN)/polyfold make examples/bunny-128.obj -o out/bunny-128
	@echo "open out/bunny-128/instructions.html (the assembly guide, also guide.pdf); print out/bunny-128/sheets.pdf at 100 %"

# two workers (the CI machine's two cores), then the tests that must run alone
test: $(STAMP)
	$(BIN)/python -m pytest -n 2 -m "not serial"
	$(BIN)/python -m pytest -m serial

bench: $(STAMP)
	$(BIN)/python bench/bench_unfold.py
	$(BIN)/python bench/bench_fold.py --seeds 5
	$(BIN)/python bench/bench_inflate_nets.py

fig3: $(STAMP)
	$(BIN)/pip install --quiet -e '.[bench]'
	$(BIN)/python bench/bench_fig3.py --out out/fig3

clean:
	rm -rf out .pytest_cache
