"""A drive test written into a configuration (``ecdsim fit drive-test -o``).

The reduced spring goes into ``[load]`` (``start_torque`` and ``end_torque`` of its line,
or ``spring_table`` where the line misstates it, with ``travel`` and the spring's
``reference_temperature``), the friction into ``[load] system_friction`` (the line over
temperature, or the one temperature's mean), and the drive's minimum available torque
into ``[budget] available`` (docs/qualification.md). With ``--config`` the user's file is
kept as written (tomlkit) with only those keys replaced; without one, a configuration
with a clearly marked placeholder ECD is written. Validated before it is written.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ecdsim.characterize.drivetest import LINEAR_TOLERANCE, DriveTestResult
from ecdsim.characterize.export import (
    ExportError,
    _half_width,
    _parse_user,
    _with_header,
    fitted_quantity,
    significant,
    toml_string,
)

SPRING_FORMS = ("auto", "linear", "table")

PLACEHOLDER_ECD = """
# PLACEHOLDER ECD: the paper's Cc-16 (section 6) so that the file runs; replace [damper]
# and [gearbox] with your damper's (e.g. from `ecdsim fit drop-test -o`).
[damper]
damping_rate = "1.3e-4 N*m*s/rad"
coulomb_friction = "7.9e-4 N*m"

[gearbox]
ratio = 380
damping_fraction = 0.26
coulomb_friction = "4.5e-4 N*m"
"""


def spring_form(result: DriveTestResult, form: str) -> str:
    """``linear`` or ``table``: ``auto`` takes the table where the reference temperature's
    spring departs from its line by more than :data:`LINEAR_TOLERANCE`."""
    if form not in SPRING_FORMS:
        raise ExportError(f"--spring {form!r}: expected one of {', '.join(SPRING_FORMS)}")
    if form != "auto":
        return form
    return "table" if result.reference().linear_deviation > LINEAR_TOLERANCE else "linear"


def _load_entries(result: DriveTestResult, form: str) -> dict[str, str]:
    """The ``[load]`` keys the drive test gives, as TOML values."""
    ref = result.reference()
    entries: dict[str, str] = {}
    if form == "linear":
        entries["start_torque"] = fitted_quantity(
            ref.start_torque.value, "N*m", _half_width(ref.start_torque)
        )
        entries["end_torque"] = fitted_quantity(
            ref.end_torque.value, "N*m", _half_width(ref.end_torque)
        )
    else:
        rows = ", ".join(
            f"[{toml_string(f'{significant(math.degrees(a))} deg')}, "
            f"{toml_string(f'{significant(max(t, 0.0))} N*m')}]"
            for a, t in ref.table()
        )
        entries["spring_table"] = f"[{rows}]"
    entries["travel"] = toml_string(f"{significant(math.degrees(ref.travel))} deg")
    entries["reference_temperature"] = toml_string(f"{significant(ref.temperature)} degC")
    law = result.friction_law
    if law is not None:
        at_0c, slope = law.parameters
        entries["system_friction"] = (
            f"{{ slope = {fitted_quantity(slope.value, 'N*m/K', _half_width(slope))}, "
            f"at_0C = {fitted_quantity(at_0c.value, 'N*m', _half_width(at_0c))} }}"
        )
    else:
        mean = ref.mean_friction
        entries["system_friction"] = (
            f'{{ slope = "0 N*m/K", at_0C = '
            f"{fitted_quantity(max(mean.value, 0.0), 'N*m', _half_width(mean))} }}"
        )
    return entries


def _available_entry(result: DriveTestResult) -> str:
    available, _, _ = result.available
    return fitted_quantity(available, "N*m")


def toml_list(items: Sequence[str]) -> str:
    """A TOML list of strings."""
    return "[" + ", ".join(toml_string(x) for x in items) + "]"


def _set(table: Any, key: str, value: str, comment: str | None = None) -> None:
    import tomlkit

    item = tomlkit.parse(f"v = {value}\n")["v"]
    table[key] = item
    if comment:
        table[key].comment(comment)


def drive_test_config_text(
    result: DriveTestResult,
    provenance: Sequence[str],
    form: str = "auto",
    user_text: str | None = None,
    config_name: str = "",
) -> str:
    """The configuration text of a drive test (module docstring)."""
    import tomlkit

    chosen = spring_form(result, form)
    entries = _load_entries(result, chosen)
    available, at_t, at_angle = result.available
    ref = result.reference()
    if user_text is not None:
        document = _parse_user(user_text)
    else:
        document = tomlkit.parse(
            f'title = "hinge from a drive test ({result.table.source})"\n' + PLACEHOLDER_ECD
        )
    load = document.get("load")
    if load is None:
        load = tomlkit.table()
        document["load"] = load
    # One spring form only: the other one's keys go.
    for key in ("start_torque", "end_torque", "spring_table"):
        if key in load and key not in entries:
            del load[key]
    for key, value in entries.items():
        _set(load, key, value)
    budget = document.get("budget")
    if budget is None:
        budget = tomlkit.table()
        document["budget"] = budget
    # The opening torque is net of the hinge's own friction: the model's FS_T must not
    # be counted against it again.
    excluded = budget.get("exclude")
    names = [str(x) for x in excluded] if excluded is not None else []
    if "system_friction" not in names:
        _set(
            budget,
            "exclude",
            toml_list([*names, "system_friction"]),
            "the drive test's available torque is net of the hinge friction",
        )
    _set(
        budget,
        "available",
        _available_entry(result),
        f"drive test: smallest opening torque, at {at_t:g} degC, {math.degrees(at_angle):.4g} deg",
    )
    friction = "the friction line over the test temperatures" if result.friction_law else (
        f"the mean friction at {ref.temperature:g} degC"
    )  # fmt: skip
    header = [
        *provenance,
        "",
        "drive test (docs/qualification.md):",
        f"[load] spring from the test at {ref.temperature:g} degC as "
        f"{'its line' if chosen == 'linear' else 'a table'}, "
        f"travel {math.degrees(ref.travel):.4g} deg;",
        f"system_friction {friction}; [budget] available = {available:.6g} N*m",
        *(
            [f"from {config_name}: every other key as written there"]
            if user_text is not None
            else ["[damper] and [gearbox] are a PLACEHOLDER: replace them with your ECD"]
        ),
    ]
    return _with_header(header, tomlkit.dumps(document))
