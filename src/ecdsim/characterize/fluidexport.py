"""A fluid damper's fitted power law written into a configuration
(``ecdsim fit fluid-damper -o``, docs/qualification.md).

With ``--config`` the user's file is kept as written (tomlkit) and its ``[fluid_damper]``
gets the measured ``power_law`` in place of a viscosity law (its name, deadband, friction
and inertia kept); without one, a configuration with the paper's example as a clearly
marked PLACEHOLDER ECD and load is written. Validated before it is written.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ecdsim.characterize.driveexport import PLACEHOLDER_ECD, toml_list
from ecdsim.characterize.export import _parse_user, _with_header, significant, toml_string
from ecdsim.characterize.fluidfit import FluidFitResult

PLACEHOLDER_LOAD = """
# PLACEHOLDER load: the paper's test hinge (section 6); replace it with yours.
[load]
start_torque = "3.73 N*m"
end_torque = "1.58 N*m"
travel = "1.57 rad"
system_friction = { slope = "-0.0044 N*m/K", at_0C = "0.58 N*m" }
"""

# Keys of [fluid_damper] that the measured power law replaces.
REPLACED = (
    "law", "dynamic_viscosity", "kinematic_viscosity", "exponent", "match_temperature",
    "match_speed", "power_law",
)  # fmt: skip


def _half(law: Any, index: int) -> float | None:
    estimate = law.parameters[index] if law is not None else None
    if estimate is None or estimate.ci95 is None:
        return None
    low, high = estimate.ci95
    return float(high - low) / 2.0


def power_law_entries(result: FluidFitResult) -> dict[str, str]:
    """The ``[fluid_damper.power_law]`` keys as TOML values, each to its significant digits."""
    constants = result.law_constants()
    log_half = _half(result.torque_law, 0)
    torque = constants["torque"]
    torque_half = None if log_half is None else torque * log_half
    temps = [f.temperature for f in result.fits]
    return {
        "reference_temperature": toml_string(f"{significant(result.reference_temperature)} degC"),
        "reference_speed": toml_string(f"{significant(result.reference_speed)} rad/s"),
        "torque": toml_string(f"{significant(torque, torque_half)} N*m"),
        "exponent": significant(constants["exponent"], _half(result.exponent_law, 0)),
        "exponent_slope": toml_string(
            f"{significant(constants['exponent_slope'], _half(result.exponent_law, 1))} / K"
        ),
        "activation": toml_string(
            f"{significant(constants['activation'], _half(result.torque_law, 1))} K"
        ),
        "temperatures": toml_list([f"{significant(t)} degC" for t in temps]),
    }


def fluid_damper_text(
    result: FluidFitResult,
    provenance: Sequence[str],
    user_text: str | None = None,
    config_name: str = "",
) -> str:
    """The configuration text with the fitted power law (module docstring)."""
    import tomlkit

    if user_text is not None:
        document = _parse_user(user_text)
    else:
        document = tomlkit.parse(
            f'title = "fluid damper from a bench test ({result.table.source})"\n'
            + PLACEHOLDER_ECD
            + PLACEHOLDER_LOAD
        )
    damper = document.get("fluid_damper")
    if damper is None:
        damper = tomlkit.table()
        document["fluid_damper"] = damper
    for key in REPLACED:
        if key in damper:
            del damper[key]
    if "name" not in damper:
        damper["name"] = "fluid damper (bench test)"
    source = f"bench test {result.table.source} (sha256 {result.table.sha256[:16]}...)"
    damper["source"] = source
    table = tomlkit.table()
    for key, value in power_law_entries(result).items():
        table.add(key, tomlkit.parse(f"v = {value}\n")["v"])
    damper["power_law"] = table
    constants = result.law_constants()
    temps = [f.temperature for f in result.fits]
    ratio = (
        f"; torque at {min(temps):g} degC = {result.torque_ratio(min(temps), max(temps)):.3g} x "
        f"that at {max(temps):g} degC"
        if len(temps) >= 2
        else ""
    )
    header = [
        *provenance,
        "",
        "fluid damper's power law fitted to the bench data (docs/qualification.md):",
        f"n = {constants['exponent']:.4g} at {result.reference_temperature:g} degC{ratio}",
        *(
            [f"from {config_name}: every other key as written there"]
            if user_text is not None
            else ["[damper], [gearbox] and [load] are a PLACEHOLDER: replace them with yours"]
        ),
    ]
    return _with_header(header, tomlkit.dumps(document))
