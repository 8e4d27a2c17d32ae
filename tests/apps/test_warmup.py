"""apps/warmup.py (`polyfold warm-up`, run by `make setup`): it reaches the kernels a first
`polyfold make` needs, so numba has them in its cache before the user's first run."""

from __future__ import annotations

import os
import subprocess
import sys

from polyfold.apps.benchpaper import kernel_signatures
from polyfold.apps.warmup import bumpy_sphere, kernels_cached, warm_up


def test_warm_up_reaches_the_kernels_of_every_stage():
    seconds = warm_up(processes=1)  # all here, so this process holds every signature
    assert set(seconds) == {"make", "fold", "segment", "inflate"} and all(s >= 0 for s in seconds.values())
    sigs = kernel_signatures()  # (entry points: a kernel called only from compiled code is linked into its caller)
    for kernel in ("unfold.kernels.local_search", "unfold.kernels.evaluate_batch", "fold.checker.segment_free",
                   "segment.merge_kernels.merge_run", "fabricate.pack._scan", "inflate.kernels.run_steps",
                   "unfold.tabroom._swap_gains"):
        assert sigs.get(kernel), f"{kernel} was not compiled (or loaded from the cache) by the warm-up"


def test_warm_up_in_two_processes_runs_every_section():
    """`make setup` on two cores: segmentation and inflation compile in a second process (the
    entry point `python -m polyfold.apps.warmup SECTION...` prints their seconds as JSON)."""
    import json

    assert set(warm_up(processes=2)) == {"make", "fold", "segment", "inflate"}
    proc = subprocess.run([sys.executable, "-m", "polyfold.apps.warmup", "segment", "inflate"], capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert set(json.loads(proc.stdout.splitlines()[-1])) == {"segment", "inflate"}


def test_bumpy_sphere_is_closed_and_seeded():
    v, f = bumpy_sphere()
    assert v.shape == (42, 3) and f.shape == (80, 3)
    v2, _ = bumpy_sphere()
    assert (v == v2).all()


def test_cli_warm_up_says_what_it_did():
    proc = subprocess.run([sys.executable, "-m", "polyfold", "warm-up"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "kernels compiled and cached" in proc.stderr


def test_kernels_cached_tells_a_cold_cache_from_a_warm_one(tmp_path):
    warm_up()
    assert kernels_cached() is True
    cold = subprocess.run([sys.executable, "-c", "from polyfold.apps.warmup import kernels_cached; print(kernels_cached())"],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "empty")})
    assert cold.returncode == 0 and cold.stdout.strip() == "False", cold.stderr
