"""Measurement through the registry and the ground-truth protocol, never naming a method:
bench, compare and its report, the stopping rule, convergence, glossiness matching."""
