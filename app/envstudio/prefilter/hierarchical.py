"""Fast hierarchical prefiltering (seed 004 §5.1, Figure 2).

The source: a mip pyramid of the lat-long map built with 2×2 boxes. Level 0 is
the map; level ℓ + 1 merges 2×2 nodes of level ℓ, up to the top level (the
first with an odd side, 1×2 for a power-of-two map). Every node n stores its
radiance sum W_n = Σ_s L_s Δω_s (exact texel solid angles, core.latlong), its
mean direction d_n (the Δω-weighted mean of its texels' directions,
normalised) and its angular radius ρ_n, an upper bound of the angle between d_n
and any texel centre in it (ρ = 0 for a texel, ρ_n = max_c ∠(d_n, d_c) + ρ_c).

The filter of one target texel r over the source: F(n) = k̂(⟨r, d_n⟩), the
kernel shape of prefilter.kernels (peak 1) sampled in the source's map space;
like the paper's finest levels, every level is evaluated on demand, only for
the nodes the descent reaches. Nodes of level 1 (2×2 texels) are not tested:
the test costs more than the four exact texel values.

The descent (§5.1): from the top level down (in practice from the coarsest
level with 128 nodes or more, since above it every node is refined anyway), a
node is accepted when the filter cannot differ by more than the threshold T
anywhere below it, and refined into its four children otherwise; level 0 is the exact texel value.
An accepted node contributes F(n) · W_n; E(r) = scale · Σ contributions.

The test is where this departs from the paper, which compares a node's filter
value with its four children's, i.e. one level down. With the filter's levels
sampled (not box-filtered from the finest level, which costs as much as the
brute force), that test passes wherever the samples of two neighbouring levels
miss a lobe narrower than their spacing: measured at 128×256, the prefiltered
map was wrong by 5 % of its mean at N = 10 and by 12 times its mean at
N = 500 (the studio map). Here the test bounds the difference to every finer
level at once: the texels under n lie within ρ_n of d_n, so their cosines to r
lie in [cos(θ + ρ_n), cos(max(θ − ρ_n, 0))], θ = ∠(r, d_n), and the filter's
spread over that interval (Kernel.spread) must be at most T. Every accepted
node is then within T of each of its texels, which bounds the error by
T · scale · W_n per node.

A second departure, for high dynamic range: a node brighter than the map's
mean, L_n = W_n / Ω_n above L̄ in any channel, is tested against T · L̄ / L_n
instead of T. The paper's threshold is a difference in BRDF values, fit for
its low dynamic range maps; beside a sun 10⁴–10⁵ times the mean, a filter
difference of 0.001 is an error of 10–100 times the mean. Nodes no brighter
than the mean keep the paper's test, so no node is accepted coarser than it
would be there. Measured on sunrise at 128×256 without this factor, the largest
difference to the brute force was 1.2–1.9 % of the mean at N = 50–500.

Target texels are processed in square tiles (``tile`` × ``tile`` texels of
one face), which descend together: the test takes the spread over the union
of the tile's intervals, [min lo, max hi], which is at least each texel's own,
so a tile is never coarser than each of its texels alone would be (and the
kernel is evaluated twice per node, not twice per texel and node). This turns
every step into dense (tile × nodes) NumPy arrays, and tiles run on every
core (prefilter.parallel).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.core import latlong
from envstudio.prefilter.brute_force import cosines_into, weighted_sums
from envstudio.prefilter.kernels import Kernel
from envstudio.prefilter.parallel import run_chunks

__all__ = ["DEFAULT_THRESHOLD", "SourcePyramid", "prefilter", "source_pyramid"]

#: The paper's threshold on filter differences (seed 004 §5.1, "Results").
DEFAULT_THRESHOLD = 1e-3
#: Nodes of the level the descent starts at (SourcePyramid.start_level).
START_NODES = 128


@dataclass(frozen=True)
class SourcePyramid:
    """The source map's mip pyramid (module docstring); index 0 is the map itself.

    Attributes
    ----------
    shapes
        (rows, columns) of each level.
    radiance
        Per level, (3, rows · columns) float32 W_n = Σ L Δω (radiance × sr).
    directions
        Per level, (3, rows · columns) float32 unit mean directions d_n.
    radii
        Per level, (2, rows · columns) float32 (cos ρ_n, sin ρ_n).
    threshold_scales
        Per level, (rows · columns,) float32 1 / max(1, L_n / L̄): the threshold's
        factor for a node brighter than the map's mean (module docstring).
    children
        Per level ℓ ≥ 1, (rows · columns, 4) int64 flat indices of its 2×2 children at
        level ℓ − 1 (index 0 holds an empty array).
    """

    shapes: tuple[tuple[int, int], ...]
    radiance: tuple[np.ndarray, ...]
    directions: tuple[np.ndarray, ...]
    radii: tuple[np.ndarray, ...]
    threshold_scales: tuple[np.ndarray, ...]
    children: tuple[np.ndarray, ...]

    @property
    def top(self) -> int:
        """Index of the coarsest level."""
        return len(self.shapes) - 1

    @property
    def start_level(self) -> int:
        """Where the descent starts: the coarsest level with at least :data:`START_NODES` nodes.

        Above it every node is refined anyway (a lobe spreads over a node that
        spans a quarter of the sphere); starting lower saves the Python steps.
        """
        for level in range(self.top, -1, -1):
            if self.shapes[level][0] * self.shapes[level][1] >= START_NODES:
                return level
        return 0


def source_pyramid(image: npt.ArrayLike) -> SourcePyramid:
    """Build the 2×2 box pyramid of a lat-long map (seed 004 §5.1, Figure 2 left).

    Parameters
    ----------
    image
        (h, w, 3) lat-long radiance.

    Returns
    -------
    SourcePyramid
        Down to the first level with an odd number of rows or columns.
    """
    img = np.asarray(image, dtype=np.float64)
    h, w = img.shape[:2]
    omega = latlong.texel_solid_angles(h, w)
    sums = img * omega[..., None]
    moment = latlong.texel_directions(h, w) * omega[..., None]
    unit = latlong.texel_directions(h, w)
    radius = np.zeros((h, w))
    # The map's mean radiance per channel, floored so that a black map divides safely.
    mean = np.maximum(sums.reshape(-1, 3).sum(axis=0) / (4.0 * np.pi), 1e-30)
    shapes, radiance, directions, radii, scales = [], [], [], [], []
    children = [np.empty((0, 4), np.int64)]
    while True:
        shapes.append((h, w))
        radiance.append(np.ascontiguousarray(sums.reshape(-1, 3).T, dtype=np.float32))
        directions.append(np.ascontiguousarray(unit.reshape(-1, 3).T, dtype=np.float32))
        # float32 rounding of the cosines is about 6e-8: widen ρ so the bound still holds.
        rho = np.minimum(radius.reshape(-1) + 1e-3 * (radius.reshape(-1) > 0), np.pi)
        radii.append(np.stack([np.cos(rho), np.sin(rho)]).astype(np.float32))
        brightness = (sums / (omega[..., None] * mean)).max(axis=-1).reshape(-1)
        scales.append((1.0 / np.maximum(brightness, 1.0)).astype(np.float32))
        if h % 2 or w % 2:
            break
        h, w = h // 2, w // 2
        fine_unit, fine_radius = unit, radius
        sums, moment, omega = _merge(sums, h, w), _merge(moment, h, w), _merge(omega, h, w)
        unit = moment / np.linalg.norm(moment, axis=-1, keepdims=True)
        blocks = fine_unit.reshape(h, 2, w, 2, 3)
        cos = np.sum(blocks * unit[:, None, :, None, :], axis=-1)
        angle = np.arccos(np.clip(cos, -1.0, 1.0)) + fine_radius.reshape(h, 2, w, 2)
        radius = angle.max(axis=(1, 3))
        i, j = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
        kids = [(2 * i + a) * (2 * w) + 2 * j + b for a in (0, 1) for b in (0, 1)]
        children.append(np.stack(kids, axis=-1).reshape(-1, 4))
    return SourcePyramid(
        tuple(shapes),
        tuple(radiance),
        tuple(directions),
        tuple(radii),
        tuple(scales),
        tuple(children),
    )


def _merge(a: np.ndarray, h: int, w: int) -> np.ndarray:
    """Sum 2×2 blocks of a (2h, 2w, ...) array into (h, w, ...)."""
    return a.reshape(h, 2, w, 2, *a.shape[2:]).sum(axis=(1, 3))


def prefilter(
    image: npt.ArrayLike | SourcePyramid,
    directions: npt.ArrayLike,
    kernel: Kernel,
    threshold: float = DEFAULT_THRESHOLD,
    *,
    tile: int = 8,
    threads: int | None = None,
    progress: bool = False,
) -> npt.NDArray[np.float32]:
    """Hierarchically prefiltered map of a lat-long source (module docstring).

    Parameters
    ----------
    image
        (h, w, 3) lat-long radiance, or its :func:`source_pyramid`.
    directions
        (faces, rows, columns, 3) unit target directions (prefilter.targets);
        tiles are square blocks of each face.
    kernel
        The filter (prefilter.kernels).
    threshold
        T in (0, 1): the largest accepted spread of the peak-1 kernel shape over
        a node (seed 004 §5.1's threshold; 0.001 in the paper).
    tile
        Edge of a tile of target texels that descend together (at most an eighth
        of the face edge).
    threads, progress
        As prefilter.parallel.run_chunks.

    Returns
    -------
    (faces, rows, columns, 3) float32
        Prefiltered radiance.
    """
    pyramid = image if isinstance(image, SourcePyramid) else source_pyramid(image)
    targets = np.asarray(directions, dtype=np.float32)
    if targets.ndim != 4 or targets.shape[-1] != 3:
        raise ValueError(
            f"target directions must be (faces, rows, columns, 3), got {targets.shape}"
        )
    faces, rows, cols = targets.shape[:3]
    # A tile spans at most an eighth of a face: on small faces (a chain's coarse levels) an
    # 8 × 8 tile covers a whole face, and the union of its lobes most of the sphere.
    tile = max(1, min(tile, rows // 8, cols // 8))
    out = np.empty((faces, rows, cols, 3), np.float32)
    tiles = [
        (f, i, j) for f in range(faces) for i in range(0, rows, tile) for j in range(0, cols, tile)
    ]

    def work(k: int) -> None:
        f, i, j = tiles[k]
        block = targets[f, i : i + tile, j : j + tile]
        sums = _descend(pyramid, block.reshape(-1, 3), kernel, np.float32(threshold))
        out[f, i : i + tile, j : j + tile] = (kernel.scale * sums).reshape(*block.shape[:2], 3)

    costs = [min(tile, rows - i) * min(tile, cols - j) for _, i, j in tiles]
    run_chunks(work, costs, threads=threads, progress=progress, desc="hierarchical")
    return out


def _descend(pyramid: SourcePyramid, queries: np.ndarray, kernel: Kernel, threshold) -> np.ndarray:
    """Σ over the accepted nodes of F · W for one tile of (t, 3) float32 targets → (t, 3)."""
    t = len(queries)
    total = np.zeros((t, 3), np.float32)
    start = pyramid.start_level
    nodes = np.arange(np.prod(pyramid.shapes[start]))
    for level in range(start, -1, -1):
        if level == 1:  # testing 2×2 texels costs more than evaluating them: descend
            nodes = pyramid.children[1][nodes].reshape(-1)
            continue
        src = pyramid.directions[level][:, nodes]
        cos = cosines_into(queries, src, np.empty((t, len(nodes)), np.float32))
        if level == 0:
            total += weighted_sums(kernel.shape_inplace(cos), pyramid.radiance[0][:, nodes])
            break
        cos_rho, sin_rho = pyramid.radii[level][:, nodes]
        sin = np.sqrt(np.maximum(1.0 - cos * cos, 0.0))
        sin *= sin_rho
        near = cos * cos_rho
        hi = np.where(cos >= cos_rho, np.float32(1.0), near + sin).max(axis=0)
        lo = np.where(-cos >= cos_rho, np.float32(-1.0), near - sin).min(axis=0)
        accept = kernel.spread(lo, hi) <= threshold * pyramid.threshold_scales[level][nodes]
        if accept.any():
            values = kernel.shape_inplace(cos[:, accept])
            total += weighted_sums(values, pyramid.radiance[level][:, nodes[accept]])
        if accept.all():
            break
        nodes = pyramid.children[level][nodes[~accept]].reshape(-1)
    return total
