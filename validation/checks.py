"""One compared number: ecdsim's value against a reference, with a tolerance and its reason."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Check:
    """ecdsim's value of one quantity of one case against an independent reference.

    Attributes
    ----------
    quantity : what is compared, e.g. "angle at t = 0.1 s"
    unit : the unit of reference, value, difference and tolerance
    reference : the reference value
    source : where the reference comes from (short label; the case names it in full)
    value : ecdsim's value
    tolerance : the largest accepted ``|value - reference|`` [unit]
    reason : why this tolerance (the reference's own accuracy, its printed digits, ...)
    known : empty, or the documented reason why the reference itself is known to be off
        by more than the tolerance (a disagreement in the source, not in ecdsim); such a
        row passes while it stays outside the tolerance and fails once it comes inside,
        so that the explanation cannot go stale (like a strict xfail)
    """

    quantity: str
    unit: str
    reference: float
    source: str
    value: float
    tolerance: float
    reason: str
    known: str = field(default="")

    @property
    def difference(self) -> float:
        """ecdsim minus reference [unit]."""
        return self.value - self.reference

    @property
    def within(self) -> bool:
        """True when ``|difference| <= tolerance`` (NaN is never within)."""
        return abs(self.difference) <= self.tolerance

    @property
    def status(self) -> str:
        """``pass``, ``FAIL``, ``known`` (documented disagreement) or ``FAIL: known gone``."""
        if self.known:
            return "FAIL: known difference gone" if self.within else "known"
        return "pass" if self.within else "FAIL"

    @property
    def failed(self) -> bool:
        """True when this check makes the validation fail."""
        return self.status.startswith("FAIL")


@dataclass(frozen=True)
class CaseResult:
    """All checks of one validation case, with what a reader needs to judge them.

    Attributes
    ----------
    name : short identifier (used in the table and the tests)
    title : one line
    source : the references' citation (repository, path, commit; or the paper's section)
    mapping : how the source's model maps onto ecdsim's
    checks : the compared numbers
    """

    name: str
    title: str
    source: str
    mapping: str
    checks: tuple[Check, ...]

    @property
    def failed(self) -> bool:
        """True when any check fails."""
        return any(check.failed for check in self.checks)
