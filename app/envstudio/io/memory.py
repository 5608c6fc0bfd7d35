"""How much memory this process may use: what the system has available, capped by the user.

``$ENVSTUDIO_MEMORY_MB`` caps it (a shared machine, a container whose limit the
kernel does not report as available memory).
"""

from __future__ import annotations

import os

from envstudio.errors import ParameterError


def available_memory() -> int:
    """Bytes a command may still allocate: MemAvailable, else free pages, capped by
    ``$ENVSTUDIO_MEMORY_MB``; a very large number where the system does not say."""
    available = _system_available()
    raw = os.environ.get("ENVSTUDIO_MEMORY_MB")
    if raw is not None:
        try:
            cap = float(raw)
        except ValueError:
            cap = float("nan")
        if not cap > 0:
            raise ParameterError(f"ENVSTUDIO_MEMORY_MB={raw!r}: expected megabytes, a number > 0")
        available = min(available, int(cap * 2**20))
    return available


def _system_available() -> int:
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 2**62


def megabytes(count: int) -> str:
    """``1.2 GB``, ``340 MB``: a byte count for a message."""
    return f"{count / 2**30:.1f} GB" if count >= 2**30 else f"{count / 2**20:.0f} MB"
