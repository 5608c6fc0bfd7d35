"""The time limit of a progressive reference, checked alike for ``--time-limit`` and the API."""

from __future__ import annotations

import math

from envstudio.errors import ParameterError
from envstudio.measure.ground_truth import MAX_TIME_LIMIT_S


def check_time_limit(value: object, name: str) -> float:
    """``value`` (a number, or its text) as seconds.

    Parameters
    ----------
    value
        The limit as given.
    name
        How the caller calls it (``--time-limit``, ``time_limit``).

    Raises
    ------
    ParameterError
        Unless a number > 0 and at most :data:`MAX_TIME_LIMIT_S`.
    """
    try:
        seconds = math.nan if isinstance(value, bool) else float(value)
    except (TypeError, ValueError, OverflowError):
        seconds = math.nan
    if not 0 < seconds <= MAX_TIME_LIMIT_S:
        raise ParameterError(
            f"{name} {value}: expected a positive number of seconds (at most {MAX_TIME_LIMIT_S:g})"
        )
    return seconds
