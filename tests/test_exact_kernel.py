"""The exact solution's fast kernels against its reference implementation (issue 13, item 1).

``ExactMethod.solve_reference`` is the clear, whole-batch implementation; the ``numpy`` and
``numba`` kernels (:mod:`ecdsim.solvers.exact_kernel`) are second implementations of the
same function. They are compared on random inputs that reach every branch: ordinary
cases (far and near log-mean branches, the series), stalls at release, mid-segment and
exactly at a breakpoint, zero-length segments, no damping, overflowing speeds and NaN.

numba is in the test extra, so the compiled kernel is always run here: a missing numba
fails this file (the import below), it is never skipped.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numba  # noqa: F401 - required: the compiled kernel must run wherever the tests run
import numpy as np
import pytest

from ecdsim._types import FloatArray
from ecdsim.solvers import EXACT, QuasiStaticProblem, exact_kernel
from tests.conftest import ROOT

# The kernels evaluate the reference's formulas; the compiled one calls the C library's
# log and log1p instead of NumPy's SIMD versions, which differ by at most an ulp or two
# per call: a handful of ulp (~1e-15) per result. 1e-12 is the agreement target
# and leaves room for sums of several segments, far below any physical resolution.
AGREEMENT = 1e-12
FIELDS = ("deployment_time", "start_speed", "end_speed", "max_speed", "stall_angle")


def random_problem(rng: np.random.Generator, n_points: int, count: int) -> QuasiStaticProblem:
    """Tabulated springs of n_points breakpoints with every kind of case mixed in."""
    steps = rng.uniform(0.05, 1.0, (n_points - 1, count))
    steps[rng.random(steps.shape) < 0.01] = 0.0  # zero-length segments
    angles = np.concatenate([np.zeros((1, count)), np.cumsum(steps, axis=0)])
    torques = rng.uniform(0.2, 4.0, (n_points, count))
    friction = rng.uniform(0.0, 1.5, count)
    damping = 10.0 ** rng.uniform(-4.0, 2.0, count)
    kind = rng.integers(0, 12, count)
    # Equal torques (the log-mean's series, x = 0) and nearly equal ones (x ~ 1e-7, 1e-5).
    torques[:, kind == 1] = torques[0, kind == 1]
    near = kind == 2
    torques[1:, near] = torques[:1, near] * (1.0 + 10.0 ** rng.uniform(-8, -4, (1, near.sum())))
    # Net torque exactly 0 at release, and exactly 0 at a later breakpoint.
    friction[kind == 3] = torques[0, kind == 3]
    friction[kind == 4] = torques[-1, kind == 4]
    # Net torques 20 decades apart (log(a) - log(b), b/a far below 1e-16).
    far = kind == 5
    friction[far] = 0.0
    torques[-1, far] = torques[0, far] * 1e-20
    # No damping, and damping so small that the speed overflows.
    damping[kind == 6] = 0.0
    damping[kind == 7] = 1e-310
    # A NaN input; and a rising spring (b > a).
    friction[kind == 8] = np.nan
    rising = kind == 9
    torques[:, rising] = np.sort(torques[:, rising], axis=0)
    # Everything else: friction high enough that some stall mid-travel.
    return QuasiStaticProblem(angles, torques, friction, damping)


def assert_agree(expected: object, found: object) -> None:
    """Same stall and solved flags, same infinities and NaNs, values within AGREEMENT."""
    for name in ("stalled", "solved_mask"):
        assert np.array_equal(getattr(expected, name), getattr(found, name)), name
    for name in FIELDS:
        a = np.asarray(getattr(expected, name), dtype=float)
        b = np.asarray(getattr(found, name), dtype=float)
        assert a.shape == b.shape, name
        assert np.array_equal(np.isnan(a), np.isnan(b)), name
        assert np.array_equal(np.isinf(a), np.isinf(b)), name
        assert np.array_equal(a[np.isinf(a)], b[np.isinf(b)]), name
        finite = np.isfinite(a)
        scale = np.maximum(np.abs(a[finite]), np.finfo(float).tiny)
        worst = float(np.max(np.abs(a[finite] - b[finite]) / scale, initial=0.0))
        assert worst <= AGREEMENT, (name, worst)


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
@pytest.mark.parametrize("n_points", [2, 3, 7])
def test_kernels_agree_with_reference_on_random_inputs(kernel: str, n_points: int) -> None:
    rng = np.random.default_rng(1300 + n_points)
    # More cases than one NumPy block, and not a multiple of it: the last block is short.
    problem = random_problem(rng, n_points, 2 * exact_kernel.BLOCK + 1001)
    # The edge cases (NaN, 1e-310 damping) warn in the reference, as they always did.
    with np.errstate(all="ignore"):
        expected = EXACT.solve(problem, "reference")
        found = EXACT.solve(problem, kernel)
    assert_agree(expected, found)
    # Every branch was reached: stalls, unsolved cases and ordinary ones.
    assert expected.stalled.any()
    assert (~expected.solved_mask).any()
    assert np.isfinite(expected.deployment_time).sum() > problem.friction.size // 3


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
def test_kernels_on_temperature_by_sample_batches(kernel: str) -> None:
    """The Monte Carlo layout: (T, N) batch, broadcast angles, a (2, T, N) torque array."""
    rng = np.random.default_rng(7)
    count = 5000
    temps = np.array([-40.0, 25.0, 100.0])[:, np.newaxis]
    factor = 1.0 - 0.001 * (temps - 25.0)
    torques = np.stack(
        np.broadcast_arrays(rng.normal(3.73, 0.06, count) * factor, 1.58 * factor + 0 * temps)
    )
    friction = 1.0 + 0.003 * (25.0 - temps) + rng.normal(0.0, 0.25, count)
    damping = rng.uniform(15.0, 30.0, count) * (1.0 - 0.004 * (temps - 25.0))
    problem = QuasiStaticProblem(np.array([0.0, 1.57]), torques, friction, damping)
    expected = EXACT.solve(problem, "reference")
    assert expected.stalled.any()
    assert not expected.stalled.all()
    assert_agree(expected, EXACT.solve(problem, kernel))


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
def test_kernels_on_scalar_and_one_dimensional_batches(kernel: str) -> None:
    scalar = QuasiStaticProblem(
        np.array([0.0, 1.57]), np.array([3.73, 1.58]), np.array(1.0), np.array(23.65)
    )
    assert_agree(EXACT.solve(scalar, "reference"), EXACT.solve(scalar, kernel))
    assert EXACT.solve(scalar, kernel).deployment_time.shape == ()
    row = QuasiStaticProblem(
        np.array([0.0, 1.57]),
        np.array([3.73, 1.58]),
        np.array([0.5, 1.0, 1.58, 2.0]),
        np.array(23.65),
    )
    assert_agree(EXACT.solve(row, "reference"), EXACT.solve(row, kernel))


@pytest.mark.parametrize("kernel", ["numpy", "numba"])
def test_kernels_against_hand_calculations(kernel: str) -> None:
    """Two closed forms: t = B*L*ln(a/b)/(a - b), and t = B*L/a for a constant torque."""
    b_rate, length = 20.0, 1.5
    problem = QuasiStaticProblem(
        np.array([0.0, length]), np.array([[3.0, 2.0], [1.0, 2.0]]), np.array(0.5), np.array(b_rate)
    )
    solution = EXACT.solve(problem, kernel)
    # Net torques 2.5 -> 0.5 (far branch) and 1.5 -> 1.5 (the series, x = 0).
    expected = [b_rate * length * math.log(2.5 / 0.5) / 2.0, b_rate * length / 1.5]
    # The log-mean's rounding: a few ulp.
    assert solution.deployment_time == pytest.approx(expected, rel=1e-14)
    assert solution.start_speed == pytest.approx([2.5 / b_rate, 1.5 / b_rate], rel=1e-15)
    assert solution.max_speed == pytest.approx([2.5 / b_rate, 1.5 / b_rate], rel=1e-15)


def test_choice_by_batch_size_and_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(exact_kernel.ENVIRONMENT, raising=False)
    monkeypatch.delenv("ECDSIM_NUMBA", raising=False)
    assert exact_kernel.choose(3) == "numpy"
    assert exact_kernel.choose(exact_kernel.NUMBA_MIN_CASES) == "numba"
    monkeypatch.setenv("ECDSIM_NUMBA", "0")  # the switch the dynamic method obeys too
    assert exact_kernel.choose(exact_kernel.NUMBA_MIN_CASES) == "numpy"
    monkeypatch.delenv("ECDSIM_NUMBA")
    monkeypatch.setenv(exact_kernel.ENVIRONMENT, "reference")
    assert exact_kernel.choose(10**7) == "reference"
    monkeypatch.setenv(exact_kernel.ENVIRONMENT, "fortran")
    with pytest.raises(ValueError, match="fortran"):
        exact_kernel.choose(3)
    with pytest.raises(ValueError, match="fortran"):
        EXACT.solve(
            QuasiStaticProblem(
                np.array([0.0, 1.0]), np.array([2.0, 1.0]), np.array(0.0), np.array(1.0)
            )
        )


def test_a_small_prediction_does_not_import_numba() -> None:
    """ecdsim deploy solves 3 cases: the NumPy kernel, without numba's import cost."""
    code = (
        "import sys\n"
        "from ecdsim.config import load_config\n"
        "from ecdsim.deployment import predict\n"
        "config = load_config('examples/paper_cc16.toml')\n"
        "predict(config.system, config.temperatures)\n"
        "assert 'numba' not in sys.modules, 'numba imported'\n"
    )
    env = {k: v for k, v in os.environ.items() if k != exact_kernel.ENVIRONMENT}
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True)


def test_large_batch_uses_numba_and_matches(monkeypatch: pytest.MonkeyPatch) -> None:
    """The automatic choice for a Monte Carlo-sized batch runs the compiled kernel."""
    monkeypatch.delenv(exact_kernel.ENVIRONMENT, raising=False)
    monkeypatch.delenv("ECDSIM_NUMBA", raising=False)
    rng = np.random.default_rng(11)
    count = exact_kernel.NUMBA_MIN_CASES
    problem = QuasiStaticProblem(
        np.array([0.0, 1.57]),
        np.stack([rng.uniform(3.0, 4.0, count), rng.uniform(1.0, 2.0, count)]),
        rng.uniform(0.0, 1.5, count),
        rng.uniform(10.0, 30.0, count),
    )
    calls: list[int] = []
    original = exact_kernel._numba_ordinary

    def counted(*args: FloatArray) -> object:
        calls.append(1)
        return original(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(exact_kernel, "_numba_ordinary", counted)
    found = EXACT.solve(problem)
    assert calls == [1]
    assert_agree(EXACT.solve(problem, "reference"), found)
