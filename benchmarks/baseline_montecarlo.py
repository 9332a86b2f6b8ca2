"""The baseline of the Monte Carlo benchmark: the bare NumPy script an engineer would write.

It samples the eight tolerances of ``examples/paper_cc16_tolerances.toml`` (the same
distributions, spreads and start/end torque correlation, written out here in SI), solves
every sample at -40, +25 and +100 degC with the paper's Eq. 1-4 and the exact
quasi-static time ``B * L / logmean(a, b)`` (docs/model.md), and prints the P1, P5, P50,
P95 and P99 deployment times per temperature as JSON. No ecdsim import, no files, no
sensitivity or repeatability statistics: the floor that ``ecdsim montecarlo`` is compared
with (issue 13, item 2). Random sampling with NumPy's default generator, in blocks of
1,000,000 samples so that its memory stays bounded too; percentiles by ``np.partition``
(the same order statistic, ceil(p*N)-th smallest, as ecdsim's).

    python benchmarks/baseline_montecarlo.py 10000000
"""

from __future__ import annotations

import json
import math
import resource
import sys
import time

import numpy as np

TEMPERATURES = (-40.0, 25.0, 100.0)  # [degC]
PERCENTILES = {"P1": 0.01, "P5": 0.05, "P50": 0.50, "P95": 0.95, "P99": 0.99}
BLOCK = 1_000_000

# The example's nominal values [SI].
BD, T_REF, BD_COEFF = 1.3e-4, 25.0, -0.004  # damper damping rate, Eq. 1
FD = 7.9e-4  # damper Coulomb friction [N*m]
FL_SLOPE, FL_0 = -2.12e-6, 2.2e-4  # lubrication friction law [N*m/K, N*m]
RATIO, BG_FRACTION, FG = 380.0, 0.26, 4.5e-4  # gearbox
TS, TE, TRAVEL = 3.73, 1.58, 1.57  # spring [N*m], travel [rad]
FS_SLOPE, FS_0 = -0.0044, 0.58  # system friction law [N*m/K, N*m]


def sample(rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
    """The eight toleranced quantities (the example's [tolerances.quantities])."""
    z_start = rng.standard_normal(n)
    z_end = 0.8 * z_start + math.sqrt(1.0 - 0.8**2) * rng.standard_normal(n)  # rho = 0.8
    return {
        "bd": BD * (1.0 + 0.10 / 3.0 * rng.standard_normal(n)),  # normal, 3 sigma 10 %
        "fd": FD * rng.uniform(0.8, 1.2, n),  # uniform +-20 %
        "fl0": FL_0 * rng.uniform(0.75, 1.25, n),  # uniform +-25 %
        "bg": rng.uniform(BG_FRACTION - 0.04, BG_FRACTION + 0.04, n),  # uniform +-0.04
        "fg": FG * rng.uniform(0.8, 1.2, n),  # uniform +-20 %
        "ts": TS * (1.0 + 0.05 / 3.0 * z_start),  # normal, 3 sigma 5 %
        "te": TE * (1.0 + 0.05 / 3.0 * z_end),  # normal, 3 sigma 5 %
        "fs0": FS_0 * (1.0 + 0.15 / 3.0 * rng.standard_normal(n)),  # normal, 3 sigma 15 %
    }


def deployment_time(s: dict[str, np.ndarray], temperature: float) -> np.ndarray:
    """Exact quasi-static deployment time [s], inf where it stalls."""
    bd_t = s["bd"] * (1.0 + BD_COEFF * (temperature - T_REF))
    damping = (bd_t + s["bg"] * s["bd"]) * RATIO**2  # Eq. 1, 3
    friction = (s["fd"] + FL_SLOPE * temperature + s["fl0"] + s["fg"]) * RATIO  # Eq. 2, 4
    friction += FS_SLOPE * temperature + s["fs0"]
    a = s["ts"] - friction
    b = s["te"] - friction
    with np.errstate(all="ignore"):
        mean = (a - b) / np.log(a / b)  # log-mean of the net torques
        time_s = damping * TRAVEL / mean
    return np.where((a > 0.0) & (b > 0.0), time_s, np.inf)


def main(samples: int, seed: int = 20240611) -> dict[str, object]:
    """Sample, solve, take percentiles; the result as a JSON-ready dict."""
    started = time.perf_counter()
    rng = np.random.default_rng(seed)
    times = np.empty((len(TEMPERATURES), samples))
    for start in range(0, samples, BLOCK):
        stop = min(start + BLOCK, samples)
        s = sample(rng, stop - start)
        for i, temperature in enumerate(TEMPERATURES):
            times[i, start:stop] = deployment_time(s, temperature)
    result: dict[str, object] = {}
    for i, temperature in enumerate(TEMPERATURES):
        ranks = [
            min(max(math.ceil(round(p * samples, 9)) - 1, 0), samples - 1)
            for p in PERCENTILES.values()
        ]
        ordered = np.partition(times[i], ranks)
        result[str(temperature)] = {
            name: float(ordered[r]) for name, r in zip(PERCENTILES, ranks, strict=True)
        }
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    return {
        "percentiles": result,
        "seconds": time.perf_counter() - started,
        "peak_rss_bytes": peak,
    }


if __name__ == "__main__":
    print(json.dumps(main(int(sys.argv[1]) if len(sys.argv) > 1 else 10_000_000)))
