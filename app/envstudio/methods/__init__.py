"""Renderers: one module per method, each registers itself with its declared parameters."""

from envstudio.methods import kautz, mirror, reference  # noqa: F401

# isort: split
from envstudio.methods import hwconv  # noqa: F401  (registered after: keys 1-3 stay)
from envstudio.methods.banks import method as _banks  # noqa: F401  (after hwconv: key 5)

# isort: split
from envstudio.methods.rsibr import method as _rsibr  # noqa: F401  (seed 002)

# isort: split
from envstudio.methods.pem import method as _pem  # noqa: F401  (seed 003)
