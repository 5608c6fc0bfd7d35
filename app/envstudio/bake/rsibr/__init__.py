"""Seed 002's radiance sphere maps: BRDFs (brdfs), CPU (cpu) and GPU (gpu) bakes, the file (bake).

brdfs declares its parameters with methods.parameters.Parameter, whose package
registers every method on import, rsibr's included, and that one imports brdfs:
the method registry is loaded first so the cycle resolves in that order.
"""

import envstudio.methods  # noqa: F401  (see above)
