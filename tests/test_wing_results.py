"""The wing's result type (ecdsim.wing.result) and pictures (ecdsim.plotting_wing).

TEST FIXTURES: the results here are the validation reference's runs
(validation/wing_reference.py) converted to :class:`WingResult` by
``validation.wing_cases.as_result``; the wing's own solver does not exist yet. They are
real deployments of real wing files, so the JSON, the table and the pictures are tested
on a stalled case (two hinges stuck), a latched one with a compliant latch and rebounds,
and the ground test of three panels.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ecdsim._types import FloatArray
from ecdsim.config.wing_schema import load_wing_config
from ecdsim.plotting_wing import plot_hinge_angles, plot_wing_shapes, write_wing_plots
from ecdsim.wing import Wing
from ecdsim.wing.result import WingCase, WingEnergy, WingEvent, WingResult
from validation.wing_cases import as_result, case

NAMES = ("wing_two_panel_stick_slip", "wing_two_panel_latches")


@pytest.fixture(scope="module")
def runs() -> dict[str, tuple[Wing, WingResult]]:
    """The reference's runs of two validation cases, as WingResults (fixtures)."""
    out = {}
    for name in NAMES:
        item = case(name)
        wing = load_wing_config(item.config).wing
        out[name] = (wing, as_result(item, tuple(h.name for h in wing.hinges)))
    return out


def test_json_of_a_stalled_and_a_latched_wing(runs: dict[str, tuple[Wing, WingResult]]) -> None:
    stalled = runs["wing_two_panel_stick_slip"][1].to_dict()
    text = json.dumps(stalled, allow_nan=False)  # no NaN or inf leaves the program
    assert json.loads(text) == stalled
    block = stalled["cases"][0]
    assert block["temperature_C"] == 25.0
    assert block["status"] == "stuck"
    assert block["stalled"] is True
    assert block["deployment_time_s"] is None  # inf as null
    assert block["stuck_hinges"] == ["root", "outer"]
    assert block["sequence"] == []
    assert block["energy_balance_error"] < 1e-8
    assert set(block["energy_J"]["friction_dissipation"]) == {"root", "outer"}
    kinds = [e["event"] for e in block["events"]]
    assert kinds[0] == "release"
    assert kinds.count("stick") == 2
    assert "series" not in block
    latched = runs["wing_two_panel_latches"][1].to_dict(series=True)
    block = latched["cases"][0]
    assert block["status"] == "latched"
    assert block["sequence"] == ["root", "outer"]
    root, outer = block["latches"]
    assert root["peak_torque_Nm"] > 0.0
    assert root["impulse_Nms"] is None
    assert outer["peak_torque_Nm"] is None
    assert outer["impulse_Nms"] < 0.0  # the latch pushes the arriving hinge back
    assert block["deployment_time_s"] == pytest.approx(outer["time_s"], rel=1e-15)
    series = block["series"]
    assert len(series["time_s"]) == len(series["angle_rad"]["outer"])
    assert series["angle_rad"]["outer"][-1] == pytest.approx(math.pi, rel=1e-9)


def test_dataframe_is_tidy(runs: dict[str, tuple[Wing, WingResult]]) -> None:
    result = runs["wing_two_panel_latches"][1]
    frame = result.to_dataframe()
    assert list(frame.columns) == ["temperature_C", "hinge", "time_s", "angle_rad", "speed_rad_s"]
    case_ = result.cases[0]
    assert len(frame) == case_.time.size * 2
    outer = frame[frame["hinge"] == "outer"]
    np.testing.assert_array_equal(outer["time_s"].to_numpy(), case_.time)
    np.testing.assert_array_equal(outer["angle_rad"].to_numpy(), case_.angle[:, 1])
    np.testing.assert_array_equal(outer["speed_rad_s"].to_numpy(), case_.speed[:, 1])


def test_result_type_refuses_what_it_cannot_hold() -> None:
    zero = np.zeros(1)
    energy = WingEnergy(zero, zero, zero, zero, zero)
    times = np.array([0.0, 1.0])
    with pytest.raises(ValueError, match="unknown status"):
        WingCase(25.0, times, np.zeros((2, 1)), np.zeros((2, 1)), (), (), "done", (), energy)
    with pytest.raises(ValueError, match="shape"):
        WingCase(25.0, times, np.zeros((3, 1)), np.zeros((3, 1)), (), (), "stuck", (), energy)
    with pytest.raises(ValueError, match="unknown wing event"):
        WingEvent(0.0, "explode")
    good = WingCase(25.0, times, np.zeros((2, 1)), np.zeros((2, 1)), (), (), "stuck", (0,), energy)
    with pytest.raises(ValueError, match="one column per hinge"):
        WingResult("w", ("a", "b"), (good,))
    assert good.deployment_time == math.inf
    assert energy.error == 0.0
    with pytest.raises(KeyError, match="no case at 30 degC"):
        WingResult("w", ("a",), (good,)).case_at(30.0)


def test_energy_error_is_relative_to_the_largest_term() -> None:
    energy = WingEnergy(
        spring_work=np.array([3.0, 1.0]),
        damper_dissipation=np.array([2.0, 0.5]),
        friction_dissipation=np.array([0.9, 0.4]),
        latch_dissipation=np.zeros(2),
        impact_loss=np.array([0.05, 0.05]),
        final_kinetic=0.1,
    )
    # Supplied 4.0, accounted 4.0 - 0.0 ... off by 0.0: build one off by 0.03.
    assert energy.supplied == pytest.approx(4.0)
    assert energy.accounted == pytest.approx(4.0)
    off = WingEnergy(**{**energy.__dict__, "final_kinetic": 0.13})
    assert off.error == pytest.approx(0.03 / 3.0)


def test_hinge_angle_plot(runs: dict[str, tuple[Wing, WingResult]], tmp_path: Path) -> None:
    wing, result = runs["wing_two_panel_latches"]
    fig = plot_hinge_angles(result, wing)
    axes = fig.axes
    assert len(axes) == 1
    ax = axes[0]
    assert ax.get_xlabel() == "time [s]"
    assert ax.get_ylabel() == "deployed angle [rad]"
    assert "deployed in 53.76 s (latch order: root, outer)" in ax.get_title()
    assert "hinge angles against time" in fig.get_suptitle()
    legend = ax.get_legend()
    assert legend is not None
    labels = [t.get_text() for t in legend.get_texts()]
    assert labels[:3] == ["root", "outer", "travel (latch)"]
    assert "latches" not in labels  # the root's latch is compliant: it engages
    assert {"compliant latch engages", "rebounds off its latch", "rebounds settle: latched"} <= (
        set(labels)
    )
    stalled_wing, stalled = runs["wing_two_panel_stick_slip"]
    title = plot_hinge_angles(stalled, stalled_wing).axes[0].get_title()
    assert "not deployed (stuck; stuck: root, outer)" in title
    paths = write_wing_plots(result, wing, tmp_path)
    assert [p.name for p in paths] == ["wing_hinge_angles.png", "wing_shapes_p25C.png"]
    assert all(p.stat().st_size > 10_000 for p in paths)


def _outline(ax: Any, gid: str) -> FloatArray:
    """The corners of the patch drawn for ``gid`` (a panel)."""
    return np.asarray(next(p for p in ax.patches if p.get_gid() == gid).get_xy(), dtype=float)


def test_shape_strip(runs: dict[str, tuple[Wing, WingResult]]) -> None:
    wing, result = runs["wing_two_panel_latches"]
    fig = plot_wing_shapes(wing, result, 25.0, times=[0.0, 20.0, 60.0])
    axes = fig.axes
    assert [ax.get_title() for ax in axes] == ["t = 0 s", "t = 20 s", "t = 60 s"]
    for ax in axes:
        assert ax.get_xlabel() == "x [m]"
        assert ax.get_aspect() == 1.0
        panels = [p for p in ax.patches if (p.get_gid() or "").startswith("panel")]
        assert len(panels) == 2  # one outline per panel
    # Stowed, both panels lie along the side (x = 0); deployed, in line out to 1 m.
    stowed = _outline(axes[0], "panel 1")
    assert np.max(np.abs(stowed[:, 0])) < 0.05
    tip = _outline(axes[2], "panel 2")
    assert np.max(tip[:, 0]) == pytest.approx(1.0, abs=0.02)
    assert "the wing's shape at +25 degC" in fig.get_suptitle()
