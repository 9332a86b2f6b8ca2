"""Numbers as short strings for table cells (CLI tables, sizing tables, HTML reports).

Only the standard library here: the CLI imports it at start-up.
"""

from __future__ import annotations

import math


def format_number(
    value: float | None, digits: int = 4, *, none: str = "-", signed_inf: bool = True
) -> str:
    """A number to ``digits`` significant figures (``g`` format) for a table cell.

    ``None`` becomes ``none``; an infinity becomes "inf", or "-inf" if it is negative and
    ``signed_inf`` is true ("inf" for both signs otherwise); NaN prints as "nan".

    >>> format_number(3.14159265)
    '3.142'
    >>> format_number(2.0e-5, 6)
    '2e-05'
    >>> format_number(None), format_number(None, none="inf")
    ('-', 'inf')
    >>> format_number(-math.inf), format_number(-math.inf, signed_inf=False)
    ('-inf', 'inf')
    """
    if value is None:
        return none
    if math.isinf(value):
        return "-inf" if signed_inf and value < 0 else "inf"
    return f"{value:.{digits}g}"


# Each deployment method in words, for the lines that name the methods under a table, in
# a report or a legend (the registry's labels are short names: "exact quasi-static").
METHOD_DESCRIPTIONS = {
    "paper": "the paper's Eq. 8-13 (the mean of the start and end speeds)",
    "exact": "the exact solution of the same quasi-static equations",
    "dynamic": "the equation of motion in time (inertia, stiction, end stop)",
}


def describe_method(name: str, label: str = "") -> str:
    """``name``'s description (:data:`METHOD_DESCRIPTIONS`), else its registry ``label``.

    >>> describe_method("exact")
    'the exact solution of the same quasi-static equations'
    >>> describe_method("mine", "my method")
    'my method'
    """
    return METHOD_DESCRIPTIONS.get(name, label or name)
