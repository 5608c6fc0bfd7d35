"""Fast hierarchical prefiltering (seed 004 §5.1, Figure 2).

The source: a mip pyramid of the lat-long map built with 2×2 boxes. Level 0 is
the map; level ℓ + 1 merges 2×2 nodes of level ℓ, up to the top level (the
first with an odd side, 1×2 for a power-of-two map). Every node n stores its
radiance sum W_n = Σ_s L_s Δω_s (exact texel solid angles, core.latlong), its
mean direction d_n (the Δω-weighted mean of its texels' directions,
normalised), its angular radius ρ_n, an upper bound of the angle between d_n
and any texel centre in it (ρ = 0 for a texel, ρ_n = max_c ∠(d_n, d_c) + ρ_c),
and radiance moments of its texel directions l_s, with w_s the sum of W_s's
channels: the centroid s_n = Σ l_s w_s / w_n (not normalised), the second moment
about it per unit weight ⟨r, S_n r⟩ = Σ w_s ⟨r, l_s − s_n⟩² / w_n, the first
moments D_n = Σ_s (l_s − s_n) ⊗ W_s (zero for the channel sum; per channel, how
far that channel's own centroid is from s_n) and a_n = max over channels of
|D_n| / W_n. All of them merge by plain sums, like the mip-map.

The filter of one target texel r over the source: F(n) = k̂(⟨r, s_n⟩), the
kernel shape of prefilter.kernels (peak 1) sampled at the node's centroid; at
level 0 that is the texel's direction, so F is the brute force's filter there.
Like the paper's finest levels, every level is evaluated on demand, only for
the nodes the descent reaches; nothing is stored per target.

The descent (§5.1): from the top level down (in practice from the coarsest
level with 128 nodes or more, since above it every node is refined anyway), a
node is accepted when the filter's value there cannot differ from its values
on the finer levels below by more than the threshold T (per unit of the node's
radiance), and refined into its four children otherwise; level 0 is the exact
texel value. An accepted node contributes F(n) · W_n; E(r) = scale · Σ of them.

The test is where this departs from the paper, which compares a node's filter
value with its four children's, i.e. one level down. With the filter's levels
sampled (not box-filtered from the finest level, which costs as much as the
brute force), that test passes wherever the samples of two neighbouring levels
miss a lobe narrower than their spacing: measured at 128×256, the prefiltered
map was wrong by 5 % of its mean at N = 10 and by 12 times its mean at
N = 500 (the studio map). Here the test bounds the difference to the finest
level at once, E_n = Σ_s (k̂(⟨r, l_s⟩) − k̂(⟨r, s_n⟩)) W_s, per unit of W_n. With
[lo, hi] = [cos(θ + ρ_n), cos(max(θ − ρ_n, 0))], θ = ∠(r, d_n), the interval that
holds the cosines of every texel under n to r (and ⟨r, s_n⟩, a convex
combination of them), and K_m a bound of |k̂⁽ᵐ⁾| over it (Kernel.derivative_bound),
a node is accepted with its filter value as it is when

1. the spread (zeroth order): k̂'s spread over [lo, hi] (Kernel.spread) is at
   most T; this passes far from the lobe, and is the only test for a tabulated
   lobe; or
2. Taylor to second order: K₁ a_n + ½ K₂ ⟨r, S_n r⟩ ≤ T. Expanding k̂(⟨r, l_s⟩)
   about ⟨r, s_n⟩ and summing with the weights W_s, the first-order term is
   k̂' ⟨r, D_n⟩ (at most K₁ a_n per unit W in each channel), the rest at most
   ½ K₂ ⟨r, S_n r⟩;

and otherwise with the first two Taylor terms added to its value,
k̂ W_n + k̂' ⟨r, D_n⟩ + ½ k̂'' ⟨r, S_n r⟩ W_n (Phong: k̂' = N k̂ / c, k̂'' = N (N − 1) k̂ / c²),
when

3. Taylor to third order: min(K₂, K₃ ρ_n / 3) ⟨r, S_n r⟩ ≤ T (the remainder is
   at most K₃/6 · max |⟨r, l_s − s_n⟩| · ⟨r, S_n r⟩ with |l_s − s_n| ≤ 2ρ_n, or
   at most K₂ ⟨r, S_n r⟩).

The second moment is the channel sum's, so tests 2 and 3 are exact for a node
of one colour and estimates for one whose colour varies inside it. Inside a wide
lobe the spread is first order in the node's size: at N = 10, where the lobe is
above T = 0.001 over 60°, every node there descended to its texels with test 1
alone (28–32 % of all texel pairs at 128×256, which held the speed-up under 3);
with tests 2 and 3 most of it is accepted as 2×2 to 8×8 nodes, and 4–5 % of the
pairs are evaluated (nodes and texels together). Like the paper's finest
levels, the filter's derivatives are evaluated on demand, only for the nodes
that test 3 accepts.

A second departure, for high dynamic range: a node brighter than the map's
mean, L_n = W_n / Ω_n above L̄ in any channel, is tested against T · L̄ / L_n
instead of T. The paper's threshold is a difference in BRDF values, fit for
its low dynamic range maps; beside a sun 10⁴–10⁵ times the mean, a filter
difference of 0.001 is an error of 10–100 times the mean. Nodes no brighter
than the mean keep the paper's test, so no node is accepted coarser than it
would be there. Measured on sunrise at 128×256 without this factor, the largest
difference to the brute force was 1.2–1.9 % of the mean at N = 50–500.

Target texels are processed in square tiles (``tile`` × ``tile`` texels of
one face) that descend together, each bounded by a cap of centre c and radius
ρ_t: a tile texel's cosine to a node's texels lies in the interval above with
θ = ∠(c, d_n) and ρ_n + ρ_t, and ⟨r, S r⟩ ≤ (√⟨c, S c⟩ + ρ_t √tr S)², so a node
accepted for the tile is accepted for each of its texels. The tests of a group
of tiles (:data:`_GROUP_TEXELS` texels) run as one set of (tile, node) pair
arrays per level, so the Python steps are per level, not per tile and level;
then each tile sums k̂ at the centroids of its accepted nodes (with the Taylor
terms where test 3 accepted them) and its texels in one dense product, as the
brute force does over texels. Groups run on every
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
    samples
        Per level, (3, rows · columns) float32 s_n = Σ_s l_s w_s / w_n, the node's
        radiance centroid (w_s the sum of W_s's channels; not normalised): where the
        filter is sampled (module docstring, "The filter's sample").
    spreads
        Per level, (6, rows · columns) float32 S_n / w_n, S_n = Σ_s (l_s − s_n)(l_s − s_n)ᵀ w_s
        the second moment about s_n, as (xx, yy, zz, 2xy, 2xz, 2yz).
    dipoles
        Per level, (rows · columns, 9) float32 D_n = Σ_s (l_s − s_n) ⊗ W_s (index 3a + channel):
        zero for the channel sum, and for each channel how far its own centroid is from s_n.
    residuals
        Per level, (rows · columns,) float32 a_n = max over channels of |D_n,channel| / W_n,channel.
    """

    shapes: tuple[tuple[int, int], ...]
    radiance: tuple[np.ndarray, ...]
    directions: tuple[np.ndarray, ...]
    radii: tuple[np.ndarray, ...]
    threshold_scales: tuple[np.ndarray, ...]
    children: tuple[np.ndarray, ...]
    samples: tuple[np.ndarray, ...]
    spreads: tuple[np.ndarray, ...]
    dipoles: tuple[np.ndarray, ...]
    residuals: tuple[np.ndarray, ...]

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
    # Radiance moments of the texel directions: Σ l ⊗ W (3 × 3), and with the channel sum
    # w: Σ w, Σ l lᵀ w (the six products of _PAIRS); each merges by plain sums.
    first = unit[..., :, None] * sums[..., None, :]
    weight = sums.sum(axis=-1)
    llw = np.stack([unit[..., a] * unit[..., b] for a, b in _PAIRS], axis=-1) * weight[..., None]
    samples, spreads, dipoles, residuals = [], [], [], []
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
        if len(shapes) == 1:  # texels: the centroid is the texel's direction, no moments
            sample, spread, dipole = unit, np.zeros((h, w, 6)), np.zeros((h, w, 9))
            residual = np.zeros((h, w))
        else:
            sample, spread, dipole, residual = _centroid_moments(unit, sums, first, weight, llw)
        residuals.append(residual.reshape(-1).astype(np.float32))
        samples.append(np.ascontiguousarray(sample.reshape(-1, 3).T, dtype=np.float32))
        spreads.append(np.ascontiguousarray(spread.reshape(-1, 6).T, dtype=np.float32))
        dipoles.append(dipole.reshape(-1, 9).astype(np.float32))
        if h % 2 or w % 2:
            break
        h, w = h // 2, w // 2
        fine_unit, fine_radius = unit, radius
        sums, moment, omega = _merge(sums, h, w), _merge(moment, h, w), _merge(omega, h, w)
        first, weight, llw = _merge(first, h, w), _merge(weight, h, w), _merge(llw, h, w)
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
        tuple(samples),
        tuple(spreads),
        tuple(dipoles),
        tuple(residuals),
    )


#: The index pairs (a, b) of a symmetric 3 × 3 matrix's six entries, in SourcePyramid.spreads.
_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def _centroid_moments(unit, sums, first, weight, llw):
    """s_n, S_n / w_n, D_n and a_n (SourcePyramid) from the raw moments of each node.

    ``unit`` (…, 3) the nodes' d_n, ``sums`` (…, 3) W_n, ``first`` (…, 3, 3) Σ l ⊗ W,
    ``weight`` (…) w_n, ``llw`` (…, 6) Σ l lᵀ w. A node of zero weight samples at d_n.
    """
    dark = weight <= 0.0
    safe = np.where(dark, 1.0, weight)[..., None]
    sample = np.where(dark[..., None], unit, first.sum(axis=-1) / safe)
    # S = Σ l lᵀ w − w s sᵀ (since Σ l w = w s), over w.
    spread = np.stack(
        [
            llw[..., k] / safe[..., 0] - sample[..., a] * sample[..., b]
            for k, (a, b) in enumerate(_PAIRS)
        ],
        axis=-1,
    )
    spread[..., :3] = np.maximum(spread[..., :3], 0.0)
    spread[..., 3:] *= 2.0
    dipole = first - sample[..., :, None] * sums[..., None, :]
    size = np.linalg.norm(dipole, axis=-2)
    residual = np.where(sums > 0.0, size / np.where(sums > 0.0, sums, 1.0), 0.0).max(axis=-1)
    return sample, spread, dipole.reshape(*sums.shape[:-1], 9), residual


def _merge(a: np.ndarray, h: int, w: int) -> np.ndarray:
    """Sum 2×2 blocks of a (2h, 2w, ...) array into (h, w, ...)."""
    top, bottom = a[0::2], a[1::2]
    return top[:, 0::2] + top[:, 1::2] + bottom[:, 0::2] + bottom[:, 1::2]


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
        T in (0, 1): the largest accepted error of a node per unit of its radiance,
        in units of the peak-1 kernel shape (seed 004 §5.1's threshold on filter
        differences; 0.001 in the paper).
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
    table = _NodeTable.of(pyramid)
    group = max(1, _GROUP_TEXELS // (tile * tile))
    groups = [tiles[g : g + group] for g in range(0, len(tiles), group)]

    def work(k: int) -> None:
        blocks = [targets[f, i : i + tile, j : j + tile] for f, i, j in groups[k]]
        sums = _descend(table, [b.reshape(-1, 3) for b in blocks], kernel, threshold)
        for (f, i, j), block, total in zip(groups[k], blocks, sums, strict=True):
            out[f, i : i + tile, j : j + tile] = (kernel.scale * total).reshape(*block.shape[:2], 3)

    costs = [sum(min(tile, rows - i) * min(tile, cols - j) for _, i, j in g) for g in groups]
    run_chunks(work, costs, threads=threads, progress=progress, desc="hierarchical")
    return out


#: Target texels per group of tiles whose descents are one set of NumPy arrays (a thread task).
_GROUP_TEXELS = 4096


@dataclass(frozen=True)
class _NodeTable:
    """Every level of a SourcePyramid in one table, level 0 first: node ids are global."""

    samples: np.ndarray  # (3, nodes) float32 s_n, where the filter is sampled
    radiance: np.ndarray  # (3, nodes) float32 W_n
    moments: np.ndarray  # (6, nodes) float32 S_n / w_n (SourcePyramid.spreads)
    dipoles: np.ndarray  # (nodes, 9) float32 D_n
    tests: np.ndarray  # (nodes, 12) float64: d_n (3), ρ_n, T's factor, a_n, S_n / w_n (6)
    children: np.ndarray  # (nodes, 4) int64 global ids of the children (level 0: -1)
    offsets: tuple[int, ...]  # first global id of each level
    start: int  # the level the descent starts at

    @staticmethod
    def of(pyramid: SourcePyramid) -> _NodeTable:
        offsets = np.cumsum([0] + [h * w for h, w in pyramid.shapes])
        kids = [np.full((offsets[1], 4), -1, np.int64)]
        kids += [offsets[k - 1] + pyramid.children[k] for k in range(1, len(pyramid.shapes))]
        cos_rho = np.concatenate([r[0] for r in pyramid.radii]).astype(np.float64)
        tests = np.concatenate(
            [
                np.concatenate(pyramid.directions, axis=1).T,
                np.arccos(np.clip(cos_rho, -1.0, 1.0))[:, None],
                np.concatenate(pyramid.threshold_scales)[:, None],
                np.concatenate(pyramid.residuals)[:, None],
                np.concatenate(pyramid.spreads, axis=1).T,
            ],
            axis=1,
            dtype=np.float64,
        )
        return _NodeTable(
            np.concatenate(pyramid.samples, axis=1),
            np.concatenate(pyramid.radiance, axis=1),
            np.concatenate(pyramid.spreads, axis=1),
            np.concatenate(pyramid.dipoles, axis=0),
            tests,
            np.concatenate(kids, axis=0),
            tuple(int(o) for o in offsets),
            pyramid.start_level,
        )


def _descend(
    table: _NodeTable, tiles: list[np.ndarray], kernel: Kernel, threshold: float
) -> list[np.ndarray]:
    """Σ over the accepted nodes of each tile's (t, 3) float32 targets → a (t, 3) per tile.

    The tests of every tile of the group run as one set of (tile, node) pair arrays,
    level by level (module docstring); then each tile sums the filter at the samples
    of its accepted nodes in one dense product, as the brute force does over texels.
    """
    centre = np.stack([q.astype(np.float64).sum(axis=0) for q in tiles])
    centre /= np.linalg.norm(centre, axis=1, keepdims=True)
    # The tile's angular radius about its centre, widened for float32 directions.
    reach = np.array(
        [np.arccos(np.clip(q @ c, -1.0, 1.0)).max() for q, c in zip(tiles, centre, strict=True)]
    )
    reach += 1e-3
    centre6 = _pairs(centre)
    first = table.offsets[table.start]
    count = table.offsets[table.start + 1] - first
    owner = np.repeat(np.arange(len(tiles)), count)
    nodes = np.tile(np.arange(first, first + count), len(tiles))
    empty = np.empty(0, np.int64)
    kept_owner, kept_nodes, flat_owner, flat_nodes = [empty], [empty], [empty], [empty]
    for _ in range(table.start, 0, -1):
        node = table.tests[nodes]
        r = reach[owner]
        angle = np.arccos(np.clip(np.einsum("pk,pk->p", centre[owner], node[:, :3]), -1.0, 1.0))
        hi = np.cos(np.maximum(angle - r - node[:, 3], 0.0)).astype(np.float32)
        lo = np.cos(np.minimum(angle + r + node[:, 3], np.pi)).astype(np.float32)
        allowed = threshold * node[:, 4]
        # ⟨r, S r⟩ over the tile: (√⟨c, S c⟩ + |r − c| √tr S)², |r − c| ≤ the tile's reach.
        quad = np.einsum("pk,pk->p", centre6[owner], node[:, 6:])
        quad = (np.sqrt(np.maximum(quad, 0.0)) + r * np.sqrt(node[:, 6:9].sum(axis=1))) ** 2
        if kernel.lut is None:
            # An unbounded derivative (inf, N < 3 at c = 0) times a zero moment is NaN, which
            # fails the comparison: no Taylor acceptance there, as wanted.
            with np.errstate(invalid="ignore"):
                curvature = kernel.derivative_bound(lo, hi, 2)
                # The filter at s_n as it is: within K₁ a_n + ½ K₂ ⟨r, S r⟩, or the spread.
                slope = kernel.derivative_bound(lo, hi, 1)
                flat = slope * node[:, 5] + 0.5 * curvature * quad <= allowed
                rest = ~flat
                flat[rest] = kernel.spread(lo[rest], hi[rest]) <= allowed[rest]
                # With the first- and second-order terms added (below), what is left is at
                # most K₃/6 · max |⟨r, l − s⟩| · ⟨r, S r⟩ (|l − s| ≤ 2ρ), or K₂ ⟨r, S r⟩.
                third = kernel.derivative_bound(lo, hi, 3) * (node[:, 3] / 3.0)
                taylor = ~flat & (np.minimum(curvature, third) * quad <= allowed)
        else:  # a tabulated lobe: the spread only
            flat = kernel.spread(lo, hi) <= allowed
            taylor = np.zeros_like(flat)
        kept_owner.append(owner[taylor])
        kept_nodes.append(nodes[taylor])
        flat_owner.append(owner[flat])
        flat_nodes.append(nodes[flat])
        refine = ~(taylor | flat)
        owner = np.repeat(owner[refine], 4)
        nodes = table.children[nodes[refine]].reshape(-1)
    # Per tile: its Taylor-accepted nodes, then the others and its texels (level 0).
    taylor_at = _by_tile(np.concatenate(kept_owner), np.concatenate(kept_nodes), len(tiles))
    plain_at = _by_tile(
        np.concatenate([*flat_owner, owner]), np.concatenate([*flat_nodes, nodes]), len(tiles)
    )
    taylored = kernel.lut is None
    second = 0.5 * kernel.exponent * (kernel.exponent - 1.0)
    sums = []
    for k, queries in enumerate(tiles):
        curved, plain = taylor_at(k), plain_at(k)
        mine = np.concatenate([curved, plain])
        cos = cosines_into(
            queries, table.samples[:, mine], np.empty((len(queries), len(mine)), np.float32)
        )
        if taylored and len(curved):
            # k̂ + k̂' ⟨r, D⟩ / W + ½ k̂'' ⟨r, S r⟩ per unit W, k̂' = N k̂ / c, k̂'' = N (N − 1) k̂ / c².
            # Below the kernel's cosine floor k̂ is a constant e^−80: no slope, no curvature.
            near = cos[:, : len(curved)]
            inverse = np.zeros_like(near)
            np.divide(np.float32(1.0), near, out=inverse, where=near > kernel.cosine_floor)
            values = kernel.shape_inplace(cos)
            ratio = values[:, : len(curved)] * inverse  # k̂ / c
            bend = _pairs(queries) @ table.moments[:, curved]
            bend *= inverse
            bend *= ratio
            values[:, : len(curved)] += np.float32(second) * bend
            ratio *= np.float32(kernel.exponent)
            dip = (ratio @ table.dipoles[curved]).reshape(len(queries), 3, 3)
            total = np.einsum("ta,tac->tc", queries, dip)
            total += weighted_sums(values, table.radiance[:, mine])
        else:
            total = weighted_sums(kernel.shape_inplace(cos), table.radiance[:, mine])
        sums.append(total)
    return sums


def _pairs(queries: np.ndarray) -> np.ndarray:
    """(t, 3) directions → (t, 6) their products in _PAIRS order: ⟨r, S r⟩ is one product."""
    return np.stack([queries[:, a] * queries[:, b] for a, b in _PAIRS], axis=1)


def _by_tile(owner: np.ndarray, nodes: np.ndarray, tiles: int):
    """k → the nodes of tile k, from (tile, node) pairs in any order."""
    order = np.argsort(owner, kind="stable")
    nodes = nodes[order]
    bounds = np.searchsorted(owner[order], np.arange(tiles + 1))
    return lambda k: nodes[bounds[k] : bounds[k + 1]]
