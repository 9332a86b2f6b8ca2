"""Render validation results as the Markdown page docs/validation.md."""

from __future__ import annotations

from collections.abc import Sequence

from ecdsim._version import __version__
from validation.checks import CaseResult, Check

INTRO = """\
# Validation

ecdsim against references that no one in this project derived: the Modelica Standard
Library's published reference results, tight scipy integrations of the same equations, and
the numbers printed in the founding paper. Each case below names its source (repository,
path and commit, or the paper's section), says how the source's model maps onto ecdsim's,
and gives each tolerance's reason. The reference data and the scripts live in
[`validation/`](../validation/); the Modelica numbers are copied with their citation into
`validation/references/*.toml`.

This page is written by `make validate` (`python -m validation --out docs/validation.md`),
which exits non-zero if any check fails; `make test` runs the same checks
(`tests/test_validation.py`). Status: **pass** within the tolerance; **FAIL** outside it;
**known**: outside the tolerance because the *reference* is known to be off (the reason is
given; the check fails if the difference ever comes inside the tolerance, so that the note
cannot go stale).
"""


def _number(x: float) -> str:
    return f"{x:.10g}"


def _row(case: CaseResult, check: Check) -> str:
    status = f"**{check.status}**" if check.status != "pass" else "pass"
    return (
        f"| {case.name} | {check.quantity} [{check.unit}] | {_number(check.reference)} | "
        f"{check.source} | {_number(check.value)} | {check.difference:+.3e} | "
        f"{check.tolerance:.2e} | {status} |"
    )


def summary(results: Sequence[CaseResult]) -> str:
    """One line: how many checks passed, are known, failed."""
    checks = [check for case in results for check in case.checks]
    failed = sum(check.failed for check in checks)
    known = sum(check.status == "known" for check in checks)
    passed = len(checks) - failed - known
    return (
        f"{len(results)} cases, {len(checks)} checks: {passed} pass, {known} known, {failed} failed"
    )


def render(results: Sequence[CaseResult]) -> str:
    """The whole page."""
    lines = [INTRO, f"ecdsim {__version__}: {summary(results)}.", ""]
    lines += [
        "| case | quantity | reference | source | ecdsim | difference | tolerance | status |",
        "|---|---|---:|---|---:|---:|---:|---|",
    ]
    lines += [_row(case, check) for case in results for check in case.checks]
    lines.append("")
    lines.append("Difference = ecdsim - reference, in the quantity's unit; tolerance likewise.")
    for case in results:
        lines += ["", f"## {case.name}: {case.title}", "", f"**Source.** {case.source}.", ""]
        lines += [f"**Mapping.** {' '.join(case.mapping.split())}", ""]
        reasons = dict.fromkeys(check.reason for check in case.checks)
        lines.append("**Tolerances.**")
        lines.append("")
        lines += [f"- {reason}" for reason in reasons]
        known = dict.fromkeys(check.known for check in case.checks if check.known)
        if known:
            lines += ["", "**Known differences in the reference.**", ""]
            lines += [f"- {note}" for note in known]
    lines.append("")
    return "\n".join(lines)
