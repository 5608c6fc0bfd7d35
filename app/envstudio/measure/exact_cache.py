"""Saved exact frames: a frame whose inputs were evaluated before is read back, not redone.

An exact frame (exact_reference.exact_frame) is a deterministic function of the footprint
samples' normals, views and tangents, the environment's pixels, the values its model reads
(exact_reference.exact_inputs) and ``ssaa``, computed by the code of
measure/exact_reference.py and measure/exact_lobes.py and the pass
shaders/reference/exact_lobe.glsl. The key is a SHA-256 of all of them, so two scenes that
ask for the same integrals share one evaluation: an atlas's Banks reference, which no Phong
exponent changes, is evaluated once for the three exponents of a scene, and a second
``compare`` of the same view costs a file read. Files are ``<cache>/exact/<key>.npz``,
written atomically with a checksum and pruned as the Monte Carlo accumulations are
(measure/ground_truth_cache.py).
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.measure import exact_lobes, exact_reference
from envstudio.measure.exact_reference import CheckedError, ExactFrame, exact_inputs
from envstudio.measure.ground_truth_cache import cache_dir, load_state, save_state
from envstudio.resources import shader_root


@functools.cache
def code_digest() -> bytes:
    """SHA-256 of the code an exact frame's value depends on: the two modules that compute
    it, the packages they build on (core, prefilter) and the shaders (reference, common)."""
    package = Path(exact_reference.__file__).parents[1]
    files = [Path(exact_reference.__file__), Path(exact_lobes.__file__)]
    for folder in (package / "core", package / "prefilter"):
        files += sorted(folder.rglob("*.py"))
    for folder in (shader_root() / "reference", shader_root() / "common"):
        files += sorted(folder.rglob("*.glsl"))
    digest = hashlib.sha256()
    for path in files:
        digest.update(path.read_bytes())
    return digest.digest()


def exact_path(
    radiance: npt.ArrayLike,
    normals: npt.ArrayLike,
    views: npt.ArrayLike,
    tangents: npt.ArrayLike | None,
    values: dict[str, object],
    ssaa: int,
) -> Path:
    """Where the exact frame of these inputs is kept (exact_reference.exact_frame's
    parameters: (h, w, 3) radiance; (H, W, 3) normals, views and tangents or None)."""
    digest = hashlib.sha256()
    for array in (radiance, normals, views, np.zeros(0) if tangents is None else tangents):
        data = np.ascontiguousarray(array)
        digest.update(str((data.dtype.str, data.shape)).encode())
        digest.update(data.tobytes())
    digest.update(repr(sorted(exact_inputs(values).items())).encode())
    digest.update(f"ssaa {ssaa}".encode())
    digest.update(code_digest())
    return cache_dir() / "exact" / f"{digest.hexdigest()[:32]}.npz"


def load_frame(path: Path) -> ExactFrame | None:
    """The frame saved at ``path``; None when absent or unreadable (discarded with a note)."""
    state = load_state(path)
    if state is None:
        return None
    median, largest, samples, min_cos, seconds = (float(x) for x in state["numbers"])
    error = CheckedError(median, largest, int(samples), min_cos)
    return ExactFrame(state["hdr"], state["mask"], error, seconds)


def save_frame(path: Path, frame: ExactFrame) -> None:
    """Keep ``frame`` at ``path`` (atomically, with a checksum; the folder pruned)."""
    error = frame.error
    numbers = [error.median, error.largest, error.samples, error.min_cos, frame.seconds]
    save_state(path, {"hdr": frame.hdr, "mask": frame.mask, "numbers": np.array(numbers)})
