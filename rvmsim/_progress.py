"""What rvmsim calls on a progress bar: :class:`ProgressBar`, the part of ``tqdm.tqdm`` it
uses (tqdm has no type information, so its bars are typed by this protocol)."""

from __future__ import annotations

from typing import Protocol, TextIO

__all__ = ["ProgressBar"]


class ProgressBar(Protocol):
    """A progress bar (``tqdm.tqdm``): ``n`` steps done so far."""

    n: float

    def update(self, n: float = 1) -> bool | None:
        """Advance by ``n`` steps."""

    def set_postfix_str(self, s: str = "", refresh: bool = True) -> None:
        """Show ``s`` after the bar."""

    def close(self) -> None:
        """End the bar (leave it or clear it, as it was made)."""

    def write(self, s: str, file: TextIO | None = None) -> None:
        """Print ``s`` above the bar (``tqdm.write``)."""
