"""Issue 26 item 5 in the PNG plots: a stall is a cross where the curve stops, in its
temperature's colour; "cannot start" at t = 0."""

from __future__ import annotations

import math

import numpy as np

from ecdsim.deployment import predict
from ecdsim.plotting import plot_deployment
from tests.conftest import paper_system

# FECD + FS at -40 degC by hand (Eq. 2-4 and the paper's FS_T, section 6):
# 380 * (7.9e-4 + 4.5e-4 + 2.2e-4 + 2.12e-6 * 40) + 0.58 + 0.0044 * 40 = 1.343024 N*m.
FRICTION_M40 = 380 * (7.9e-4 + 4.5e-4 + 2.2e-4 + 2.12e-6 * 40) + 0.58 + 0.0044 * 40


def _crosses(fig: object) -> list[tuple[float, float, object]]:
    ax = fig.axes[0]  # type: ignore[attr-defined]
    return [
        (float(line.get_xdata()[0]), float(line.get_ydata()[0]), line.get_color())
        for line in ax.get_lines()
        if line.get_marker() == "x" and len(line.get_xdata()) == 1
    ]


def test_a_stall_is_marked_where_the_curve_stops() -> None:
    # The spring falls linearly 3.73 -> 1.2 N*m over 1.57 rad: at -40 degC it meets the
    # friction at (3.73 - 1.343024) * 1.57 / (3.73 - 1.2) rad, by hand; at 100 degC never.
    prediction = predict(paper_system(end_torque=1.2), [-40.0, 100.0], ["paper", "exact"])
    fig = plot_deployment(prediction)
    stall = math.degrees((3.73 - FRICTION_M40) * 1.57 / (3.73 - 1.2))
    crosses = _crosses(fig)
    assert len(crosses) == 2  # paper and exact at -40 degC, none at 100 degC
    lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
    for (x, y, color), name in zip(
        crosses, ("paper (Eq. 8-13)", "exact quasi-static"), strict=True
    ):
        # The solvers' stall angle is the same closed form: rounding only.
        assert abs(y - stall) < 1e-9 * stall
        line = lines[f"-40 degC, {name}"]
        times = np.asarray(line.get_xdata(), dtype=float)
        angles = np.asarray(line.get_ydata(), dtype=float)
        reached = np.flatnonzero(angles >= 0.995 * stall)
        assert x == (times[reached[0]] if reached.size else times[-1])
        assert color == line.get_color()  # the temperature's colour, not one red
    legend = fig.axes[0].get_legend()
    assert legend is not None
    labels = [t.get_text() for t in legend.get_texts()]
    assert "stalls here (cannot start: t = 0)" in labels


def test_cannot_start_is_marked_at_release() -> None:
    # Start torque 1.2 N*m < 1.343024 N*m of friction at -40 degC: stalls at 0 rad.
    prediction = predict(paper_system(start_torque=1.2, end_torque=1.2), [-40.0], ["exact"])
    (cross,) = _crosses(plot_deployment(prediction))
    assert cross[:2] == (0.0, 0.0)
