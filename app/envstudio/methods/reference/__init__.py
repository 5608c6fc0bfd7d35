"""Method ``reference``: the ground truth (method), its sample allocation and tracing, plugin."""
