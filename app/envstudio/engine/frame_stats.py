"""The timing of one frame: milliseconds per pass and the clock that measured them."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class FrameStats:
    """Timing of one frame in milliseconds per pass, and the clock used."""

    passes_ms: dict[str, float]
    clock: str

    @property
    def total_ms(self) -> float:
        """Sum of the passes."""
        return sum(self.passes_ms.values())
