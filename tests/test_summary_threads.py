"""A run summary's sums of squares do not depend on the BLAS thread count (``np.dot`` splits its sum by threads,
so the last bits of an RMS followed the machine): the same array summed in processes with 1 and 4 BLAS threads
gives the same bits, and the sum equals the exactly rounded ``math.fsum`` to a relative 1e-12."""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np

CODE = ("import numpy as np; from twin.summary import _sum_sq; "
        "x = np.random.default_rng(7).standard_normal(2_000_003) * 1e3; print(_sum_sq(x).hex())")


def _run(threads: int) -> str:
    env = {**os.environ, "OMP_NUM_THREADS": str(threads), "OPENBLAS_NUM_THREADS": str(threads),
           "MKL_NUM_THREADS": str(threads)}
    return subprocess.run([sys.executable, "-c", CODE], env=env, capture_output=True, text=True,
                          check=True).stdout.strip()


def test_sum_of_squares_has_the_same_bits_for_any_thread_count():
    assert _run(1) == _run(4)


def test_sum_of_squares_is_the_sum_of_squares():
    from twin.summary import _sum_sq

    x = np.random.default_rng(3).standard_normal(100_001) * 1e3
    exact = math.fsum(float(v) * float(v) for v in x)
    assert abs(_sum_sq(x) - exact) <= 1e-12 * exact
    assert _sum_sq(np.zeros(0)) == 0.0 and _sum_sq(np.array([3.0, 4.0], dtype=np.float32)) == 25.0
