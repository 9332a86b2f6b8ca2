"""The user-facing error for bad input: one readable line per problem."""

from __future__ import annotations


class ConfigError(ValueError):
    """A configuration (or other user input) has one or more problems.

    ``problems`` holds one line per problem, each naming the key, the value and the
    expected unit. The CLI prints them and exits with code 2.
    """

    def __init__(self, problems: list[str], source: str | None = None) -> None:
        self.problems = list(problems)
        self.source = source
        prefix = f"{source}: " if source else ""
        super().__init__("\n".join(prefix + p for p in self.problems))
