"""Method ``hwconv`` (seed 004 §5.2): radii (no GL), convolution (GPU passes), method."""

from envstudio.methods.hwconv import method  # noqa: F401  (registers the method)
