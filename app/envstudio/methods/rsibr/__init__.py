"""Method ``rsibr``: seed 002 reflection-space image-based rendering (method, generator)."""
