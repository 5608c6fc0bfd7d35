"""Method ``mirror``: Blinn–Newell mirror reflection with seed 000 eq. 8 (method, plugin)."""
