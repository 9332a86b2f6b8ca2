"""Non-fatal findings of a fit: one structured record per finding, never a print."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class FitWarning:
    """A flag raised while fitting, with a readable message.

    Attributes
    ----------
    code : machine-readable kind ("roll_off", "outlier", "inertia_correction", ...)
    message : one readable sentence
    temperature_C : the temperature concerned [degC]; None if not specific to one
    """

    code: str
    message: str
    temperature_C: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {"code": self.code, "message": self.message, "temperature_C": self.temperature_C}
