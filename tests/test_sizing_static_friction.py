"""Breakaway of the ECD and of the system friction with their own factors (issue 11, 5b).

Whether a mechanism can start decides the sizing's "cannot start" (docs/sizing.md
section 1); in the dynamic method the breakaway (static) friction decides it at release.
``[damper] static_friction_factor`` used to multiply the whole kinetic friction FECD_T +
FS_T, although FS_T (hinge, harness) is not the damper's breakaway. Now each has its own:
breakaway = f_D * FECD_T + f_S * FS_T, with ``[load] static_friction_factor`` = f_S
defaulting to f_D (one factor for both, today's meaning).
"""

from __future__ import annotations

import pytest

from ecdsim.config import ConfigError, parse_config
from ecdsim.deployment import predict
from ecdsim.dynamics import DynamicParameters
from ecdsim.dynamics.method import DynamicSolution
from tests.conftest import PAPER_CONFIG
from tests.dynamics_reference import toy_system

FECD, FS = 0.6, 0.4  # kinetic frictions at the input shaft [N*m]; their sum is 1.0


@pytest.mark.parametrize(
    ("damper_factor", "system_factor", "start_torque", "sticks"),
    [
        # One factor for both (the default): breakaway 1.5 * (0.6 + 0.4) = 1.5 >= 1.4.
        (1.5, None, 1.4, True),
        # The system friction at its kinetic level: 1.5 * 0.6 + 1.0 * 0.4 = 1.3 < 1.4.
        (1.5, 1.0, 1.4, False),
        # A sticky hinge, a damper without breakaway: 1.0 * 0.6 + 2.0 * 0.4 = 1.4.
        (1.0, 2.0, 1.35, True),
        (1.0, 2.0, 1.45, False),
    ],
)
def test_each_friction_breaks_away_at_its_own_factor(
    damper_factor: float, system_factor: float | None, start_torque: float, sticks: bool
) -> None:
    # End torque 1.2 N*m > kinetic 1.0 N*m: once it breaks away it keeps moving.
    system = toy_system(20.0, FS, start_torque, 1.2, 1.0, ecd_friction=FECD)
    params = DynamicParameters(
        load_inertia=2.0,
        static_friction_factor=damper_factor,
        system_static_friction_factor=system_factor,
    )
    solution = predict(system, [25.0], ["dynamic"], dynamics=params).solutions["dynamic"]
    assert isinstance(solution, DynamicSolution)
    result = solution.result
    assert bool(result.stuck[0]) is sticks
    expected = ["release", "stick"] if sticks else ["release", "breakaway", "arrive", "latch"]
    assert result.events.names() == expected


def test_config_key_and_its_default() -> None:
    base = PAPER_CONFIG.read_text().replace("[load]\n", '[load]\ninertia = "5 kg*m^2"\n', 1)
    assert "inertia" in base
    default = parse_config(base).spec.dynamics()
    assert default is not None
    assert default.system_static_friction_factor is None  # = the damper's factor
    given = parse_config(base.replace("[load]\n", "[load]\nstatic_friction_factor = 1.3\n", 1))
    params = given.spec.dynamics()
    assert params is not None
    assert params.system_static_friction_factor == 1.3
    assert params.static_friction_factor == 1.0
    with pytest.raises(ConfigError) as raised:
        parse_config(base.replace("[load]\n", "[load]\nstatic_friction_factor = 0.9\n", 1))
    (line,) = raised.value.problems
    assert "load.static_friction_factor" in line
    assert "must be >= 1" in line
    with pytest.raises(ValueError, match="system_static_friction_factor must be >= 1"):
        DynamicParameters(load_inertia=1.0, system_static_friction_factor=0.5)
