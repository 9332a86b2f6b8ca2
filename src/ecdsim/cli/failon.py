"""``--fail-on stall,requirements``: an exit code for pipelines.

A command given ``--fail-on`` prints its results as usual, then exits with code 1 if
any case stalls (``stall``) or misses a requirement of the config's ``[requirements]``
(``requirements``), with one ``fail:`` line on stderr per reason, and 0 otherwise. A bad
value is a user error (one line, exit 2) reported before anything is computed.

Only typer is imported at start-up; the library inside the functions.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, NoReturn

import typer

if TYPE_CHECKING:
    from ecdsim.config import Config
    from ecdsim.deployment import Prediction
    from ecdsim.sizing.search import Evaluation

FAILED = 1  # the exit code when a --fail-on condition is met
CONDITIONS = ("stall", "requirements")

FailOnOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--fail-on",
        help="Exit with code 1 if any case stalls or misses a requirement: stall, "
        "requirements, or both (comma-separated or repeated).",
        metavar="WHAT",
    ),
]


def parse(values: list[str] | None) -> frozenset[str]:
    """The conditions asked for; an unknown one exits with code 2 and one line."""
    from ecdsim.cli.common import fail

    chosen: set[str] = set()
    for value in values or []:
        for item in value.split(","):
            name = item.strip()
            if name not in CONDITIONS:
                fail(
                    [
                        f"--fail-on: {name!r} is not a condition; expected stall, requirements "
                        "or both, e.g. --fail-on stall,requirements"
                    ]
                )
            chosen.add(name)
    return frozenset(chosen)


def require_requirements(conditions: frozenset[str], config: Config) -> None:
    """``--fail-on requirements`` on a config without ``[requirements]``: exit 2."""
    from ecdsim.cli.common import fail

    if "requirements" in conditions and config.spec.requirements is None:
        fail(
            [
                f"--fail-on requirements: {config.source} has no [requirements] section to "
                "check (docs/sizing.md); give one or use --fail-on stall"
            ]
        )


def stall_reasons(prediction: Prediction) -> list[str]:
    """One line per method that stalls, or sticks for good, at some temperature."""
    document = prediction.to_dict()
    reasons = []
    for method in document["methods"]:
        temps = []
        for case in document["cases"]:
            block = case[method]
            if block["stalled"] or block.get("stuck"):
                temps.append(f"{case['temperature_C']:g}")
        if temps:
            reasons.append(f"stall: the {method} method stalls at {', '.join(temps)} degC")
    return reasons


def requirement_reasons(config: Config) -> list[str]:
    """One line per requirement the config's damper and gearbox miss (the same
    evaluation as ``ecdsim size`` and the report: exact method, the requirements'
    temperatures)."""
    from ecdsim.sizing.requirements import Requirements
    from ecdsim.sizing.search import evaluate, stack_ecd

    spec = config.spec.requirements
    if spec is None:
        return []
    requirements = Requirements.from_spec(spec)
    ecd = stack_ecd([config.system.ecd.damper], [config.system.ecd.gearbox])
    evaluation = evaluate(ecd, config.system.load, requirements)
    return evaluation_reasons(evaluation, 0)


def evaluation_reasons(evaluation: Evaluation, index: int) -> list[str]:
    """One line per check of candidate ``index`` of an evaluation that fails somewhere."""
    import numpy as np

    temps = [float(t) for t in np.ravel(evaluation.temperatures)]
    reasons = []
    for check in evaluation.checks:
        if not bool(np.ravel(check.applicable)[index]):
            continue
        margins = np.asarray(check.margins)[index]
        missed = [f"{t:g}" for t, m in zip(temps, np.ravel(margins), strict=True) if not m >= 0.0]
        if missed:
            reasons.append(f"requirements: {check.label} missed at {', '.join(missed)} degC")
    return reasons


def finish(conditions: frozenset[str], reasons: list[str]) -> None:
    """Print the reasons (``fail:`` lines on stderr) and exit 1 if there are any."""
    if not conditions or not reasons:
        return
    exit_failed(reasons)


def exit_failed(reasons: list[str]) -> NoReturn:
    """``fail: ...`` lines on stderr, exit code 1."""
    for reason in reasons:
        typer.echo(f"fail: {reason}", err=True)
    raise typer.Exit(FAILED)
