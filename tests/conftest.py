"""Shared fixtures: the paper's Cc-16 example built directly from the paper's constants."""

from __future__ import annotations

from pathlib import Path

import pytest

from ecdsim.model import (
    DeploymentSystem,
    Ecd,
    Gearbox,
    HighSpeedDamper,
    LinearSpring,
    LinearTemperatureLaw,
    Load,
)

ROOT = Path(__file__).resolve().parent.parent
PAPER_CONFIG = ROOT / "examples" / "paper_cc16.toml"


def paper_system(**load_overrides: float) -> DeploymentSystem:
    """The paper's section 6 example, every constant as printed in the paper."""
    damper = HighSpeedDamper(
        damping_rate=1.3e-4,
        coulomb_friction=7.9e-4,
        lubrication_friction=LinearTemperatureLaw(slope=-2.12e-6, at_0c=2.2e-4),
    )
    gearbox = Gearbox(ratio=380.0, coulomb_friction=4.5e-4, damping_fraction=0.26)
    start = load_overrides.get("start_torque", 3.73)
    end = load_overrides.get("end_torque", 1.58)
    travel = load_overrides.get("travel", 1.57)
    load = Load(
        spring=LinearSpring(start, end),
        travel=travel,
        system_friction=LinearTemperatureLaw(slope=-0.0044, at_0c=0.58),
    )
    return DeploymentSystem(Ecd(damper, gearbox), load, name="paper Cc-16")


@pytest.fixture
def paper() -> DeploymentSystem:
    """The paper's example system."""
    return paper_system()
