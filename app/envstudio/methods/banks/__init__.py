"""Method ``banks``: anisotropic prefiltered environment maps, Banks model (seed 004 §5.3)."""
