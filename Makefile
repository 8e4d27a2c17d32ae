# One-command entry points. Both create ./.venv on a fresh machine (only Python 3.11 + pip needed).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: setup demo test bench fig3 clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
# the packages' bytecode compiled on every core at once, not by pip on one (35 s of pip's 61 s on
# a slow machine: 19.5 s this way); the same files. (Not left to Python's first imports: where
# PYTHONDONTWRITEBYTECODE is set, as on this project's machines, nothing would ever write it.)
	$(BIN)/pip install --quiet --no-compile -e '.[test,viewer,batch,bench]'
	$(BIN)/python -c "import compileall, sysconfig; compileall.compile_dir(sysconfig.get_paths()['purelib'], quiet=2, workers=0)"
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
