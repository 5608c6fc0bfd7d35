"""The default ``--size`` of a map with a ``--border`` (``prefilter``, ``envmap``): valid
whatever the border (issue 38: a default valid for every valid value of the other options)."""

from __future__ import annotations

__all__ = ["default_size"]


def default_size(size: int | None, border: int, smallest: int) -> int:
    """``--size``, or where not given ``smallest``, or more where a paraboloid's ``--border``
    needs it (border < size/2): a default valid whatever the border.

    Parameters
    ----------
    size
        ``--size`` as given (None: not given).
    border
        ``--border``.
    smallest
        The command's default size.
    """
    return size if size is not None else max(smallest, 2 * border + 2)
