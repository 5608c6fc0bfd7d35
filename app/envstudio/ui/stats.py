"""A short history of frame and pass times for the Stats panel's graph."""

from __future__ import annotations

from collections import deque

import numpy as np
import numpy.typing as npt

from envstudio.engine.frame_stats import FrameStats

FRAME_SERIES = "frame"
"""Name of the whole-frame series (CPU time between frames)."""


class FrameHistory:
    """The last ``length`` frames: frame time and each pass's time in milliseconds.

    The series are those of the latest frame; when the set of passes changes
    (another method, background switched off) the history starts again, so
    every series covers the same frames.

    Parameters
    ----------
    length
        Frames kept.
    """

    def __init__(self, length: int = 240):
        self.length = length
        self.clock = ""
        self._series: dict[str, deque[float]] = {}

    def add(self, frame_ms: float, stats: FrameStats) -> None:
        """Record one frame: ``frame_ms`` between frames and the passes of ``stats``."""
        names = [FRAME_SERIES, *stats.passes_ms]
        if list(self._series) != names:
            self._series = {name: deque(maxlen=self.length) for name in names}
        self._series[FRAME_SERIES].append(frame_ms)
        for name, ms in stats.passes_ms.items():
            self._series[name].append(ms)
        self.clock = stats.clock

    def series(self) -> dict[str, npt.NDArray[np.float64]]:
        """Name → (n,) float64 milliseconds, oldest first; ``frame`` comes first."""
        return {name: np.array(values, dtype=np.float64) for name, values in self._series.items()}

    def latest(self) -> dict[str, float]:
        """Name → milliseconds of the newest frame (empty before the first)."""
        return {name: values[-1] for name, values in self._series.items() if values}
