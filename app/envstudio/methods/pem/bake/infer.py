"""EM inference for a PEM bake: EM geometries, the rendering matrix, the solve (seed 003 §4).

Seed 003 §4 ("EM Inference") models the playback renderer as a linear map A,
the *rendering matrix*, from environment-map texels to display pixels, and
finds the least-squares EM x whose playback matches the ray tracer's segmented
layer b (here the distant layer of one reflector part, Figure 4)::

    min_x ||A x − b||² + λ ||D x||²

D is the texel-difference operator of the cube map (the "smoothness"
regularisation that fills non-contributing texels from their neighbours, §4
citing [10]). The normal equations (AᵀA + λ DᵀD) x = Aᵀb are solved per colour
channel by conjugate gradient (:func:`scipy.sparse.linalg.cg`, Jacobi
preconditioned); in :func:`infer_em` the range term is a clip of the solution
to x ≥ 0, in :func:`solve_mip` bounds kept by an active set.

EM geometries (§4, "EM Representations", "Layered EMs")
-------------------------------------------------------
- :class:`BoxGeometry`: the distant layer's box map, "aligned to the room, bottom
  on the floor". :func:`distant_box` takes the scene's room (a local node whose
  mesh is the ``room`` primitive); without one, the box around the local
  objects and reflectors, bottom on their lowest point; with neither, a large
  cube about the reflectors.
- :class:`EllipsoidGeometry`: the local layer's "axis-aligned bounding ellipsoid
  centered at the object centroid with axis scales that minimize resulting
  volume, determined using brute force optimization" (§4, "Layered EMs"):
  :func:`min_volume_ellipsoid`.

Both are indexed through a cube map (:mod:`envstudio.core.cubemap`) by the
vector from the EM origin — "an area-weighted average of the object's triangle
centroids" (:func:`em_origin`) — to the point where the reflection ray leaves
the geometry (§4, "EM Representations": normalisation is not needed).

The rendering matrix (:func:`rendering_matrix`)
-----------------------------------------------
For every sample of the part (:attr:`TracedView.ray_point`, ``ray_direction``),
the reflection ray is intersected with the geometry and its lookup vector
bilinearly weighted over the four nearest texels of its cube face (texel centres
at ((j + ½)/n, (i + ½)/n), clamped to the face edge as ``GL_CLAMP_TO_EDGE``
samples a face). A pixel's row is the mean of its part samples' weights, the same
mean the tracer takes for the distant layer, so the rows of covered pixels sum to 1.
This per-sample, finest-level matrix (:func:`rendering_matrix`, :func:`infer_em`,
:func:`infer_distant`) is the single-level check of the solve; the bake itself
uses the playback's lookups (one per pixel, trilinear over every level:
:mod:`envstudio.methods.pem.bake.lookups`) and solves all levels at once.

All MIP levels at once (§4, "EM MIPMAPs")
-----------------------------------------
:func:`solve_mip` solves (AᵀA + λ DᵀD + μ TᵀT) x = Aᵀb for the concatenated
levels x, D the seam-crossing smoothness of each level (block diagonal) and T
:func:`mip_ties` (each coarse texel against the 2 × 2 mean of the level below,
weak, so levels nothing looks up are defined), with range bounds kept by an
active set (:func:`bounded_cg`). From 128² EMs (:data:`MULTIGRID_SIZE`) its CG is
preconditioned by a multigrid V-cycle (:class:`ChainMultigrid`, not in seed 003)
instead of Jacobi: the regulariser is a Laplacian, whose fill of the texels no
pixel reaches takes Jacobi-CG O(n) iterations (600–1500 at 256², 30–160 with
the cycle; studies/pem-paper-scale/README.md). :func:`infer_mip` wraps it for one layer;
:func:`infer_local_over` fits the local layer's premultiplied RGBA through the
"over" with the inferred distant layer.

Coupled inference (issue 31; *not in seed 003*, which infers each view alone)
-----------------------------------------------------------------------------
Views inferred alone disagree where the trace leaves the solve free (texels few
pixels reach), and the playback's blend between them wobbles. The joint problem
over all views v with neighbours N(v) on the view grid,

    Σ_v ||A_v x_v − b_v||² + x_vᵀ R x_v + (γ/2) Σ_v Σ_{w∈N(v)} ||x_v − x_w||²,

is solved by alternating passes (red-black block Gauss–Seidel,
methods/pem/bake/bake.py): each view re-solved with its neighbours' latest maps
held fixed, which adds γ|N(v)| I to the
normal matrix and γ Σ_w x_w to the right-hand side (:func:`solve_mip`'s
``anchor`` = the neighbours' mean and ``coupling`` = γ|N(v)|). γ = 0 is the
independent solve, the very same arithmetic (the term is not even added).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import numpy.typing as npt
from scipy import linalg as sla
from scipy import sparse
from scipy.sparse import linalg as splinalg
from threadpoolctl import threadpool_limits

from envstudio.core.cubemap import direction_to_uv, uv_to_direction
from envstudio.methods.pem.bake.mip import level_offsets, mip_sizes
from envstudio.methods.pem.bake.trace import SceneTracer, TracedView
from envstudio.scene.graph import Scene

__all__ = [
    "MULTIGRID_SIZE",
    "BoxGeometry",
    "ChainMultigrid",
    "EMInference",
    "EllipsoidGeometry",
    "MipInference",
    "bounded_cg",
    "cube_bilinear",
    "distant_box",
    "em_origin",
    "infer_distant",
    "infer_em",
    "infer_local_over",
    "infer_mip",
    "local_ellipsoid",
    "min_volume_ellipsoid",
    "mip_regulariser",
    "mip_ties",
    "part_triangles",
    "psnr",
    "rendering_matrix",
    "smoothness_operator",
    "solve_mip",
]


# -- EM geometries ----------------------------------------------------------------------


@dataclass(frozen=True)
class BoxGeometry:
    """An axis-aligned box map (seed 003 §4, "EM Representations").

    Attributes
    ----------
    lo, hi : (3,) float64
        Opposite corners, world space.
    """

    lo: npt.NDArray[np.float64]
    hi: npt.NDArray[np.float64]

    def exit_distance(self, origins: npt.ArrayLike, directions: npt.ArrayLike) -> np.ndarray:
        """Ray parameter where rays leave the box (slab method).

        Parameters
        ----------
        origins, directions
            (k, 3) float, world space.

        Returns
        -------
        (k,) float64
            t ≥ 0 of the exit point, NaN where the ray misses the box or the box
            lies behind it.
        """
        o = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (self.lo - o) / d
            t2 = (self.hi - o) / d
        far = np.where(np.isnan(t1), np.inf, np.maximum(t1, t2)).min(axis=1)
        near = np.where(np.isnan(t1), -np.inf, np.minimum(t1, t2)).max(axis=1)
        ok = np.isfinite(far) & (far >= np.maximum(near, 0.0))
        return np.where(ok, far, np.nan)

    def volume(self) -> float:
        """Volume of the box."""
        return float(np.prod(self.hi - self.lo))


@dataclass(frozen=True)
class EllipsoidGeometry:
    """An axis-aligned ellipsoid map Σ ((x − c)_k / r_k)² = 1 (seed 003 §4, Figure 3).

    Attributes
    ----------
    centre : (3,) float64
        World-space centre c.
    radii : (3,) float64
        Semi-axes r along x, y, z.
    """

    centre: npt.NDArray[np.float64]
    radii: npt.NDArray[np.float64]

    def exit_distance(self, origins: npt.ArrayLike, directions: npt.ArrayLike) -> np.ndarray:
        """Ray parameter of the far intersection with the ellipsoid.

        Parameters
        ----------
        origins, directions
            (k, 3) float, world space.

        Returns
        -------
        (k,) float64
            The larger root t of the ray–ellipsoid quadratic, NaN where it is
            negative or the ray misses.
        """
        o = (np.asarray(origins, dtype=np.float64).reshape(-1, 3) - self.centre) / self.radii
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3) / self.radii
        a = np.einsum("ij,ij->i", d, d)
        b = np.einsum("ij,ij->i", o, d)
        c = np.einsum("ij,ij->i", o, o) - 1.0
        disc = b * b - a * c
        with np.errstate(invalid="ignore", divide="ignore"):
            t = (-b + np.sqrt(disc)) / a
        return np.where((disc >= 0) & (t >= 0), t, np.nan)

    def volume(self) -> float:
        """4/3 π r_x r_y r_z."""
        return float(4.0 / 3.0 * np.pi * np.prod(self.radii))

    def contains(self, points: npt.ArrayLike, tol: float = 1e-9) -> np.ndarray:
        """(k,) bool: Σ ((p − c)_k / r_k)² ≤ 1 + tol for (k, 3) points."""
        q = (np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.centre) / self.radii
        return np.einsum("ij,ij->i", q, q) <= 1.0 + tol


def em_origin(triangles: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The EM origin: the area-weighted mean of triangle centroids (seed 003 §4).

    Parameters
    ----------
    triangles
        (m, 3, 3) float, world-space corners.

    Returns
    -------
    (3,) float64
        The origin; the plain mean of the corners when every triangle is degenerate.
    """
    tri = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    if len(tri) == 0:
        raise ValueError("an EM origin needs at least one triangle")
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    centroids = tri.mean(axis=1)
    if area.sum() <= 0:
        return centroids.mean(axis=0)
    return (area[:, None] * centroids).sum(axis=0) / area.sum()


def min_volume_ellipsoid(
    points: npt.ArrayLike,
    centre: npt.ArrayLike,
    levels: int = 12,
    grid: int = 17,
) -> EllipsoidGeometry:
    """The minimum-volume axis-aligned ellipsoid about ``centre`` bounding ``points``.

    Seed 003 §4 ("Layered EMs"): centred at the object centroid, axis scales that
    minimise the volume, found by brute-force search. With semi-axes
    r = s·(e^{a₁}, e^{a₂}, e^{−a₁−a₂}) the volume is ∝ s³ and the smallest s that
    bounds every point is s² = max_i Σ_k (p_ik − c_k)² e^{−2a_k}, a convex
    function of (a₁, a₂). A ``grid`` × ``grid`` search over (a₁, a₂) is refined
    ``levels`` times about the best node (the window shrinks by 4 each time), so it
    converges to the global minimum. Only the convex-hull vertices are tested.

    Parameters
    ----------
    points
        (N, 3) float, world space (the part's vertices).
    centre
        (3,) float, the ellipsoid's centre (the EM origin).
    levels, grid
        Refinements and nodes per axis of the search.

    Returns
    -------
    EllipsoidGeometry
        It contains every point (the scale is taken as the exact maximum, then
        widened by 1e-9 relative).
    """
    c = np.asarray(centre, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(p) == 0:
        raise ValueError("a bounding ellipsoid needs at least one point")
    try:
        from scipy.spatial import ConvexHull

        p = p[ConvexHull(p).vertices]
    except Exception:  # degenerate (flat or too few points): test every point
        pass
    q = (p - c) ** 2  # (N, 3)
    half = np.sqrt(q.max(axis=0))
    floor = max(float(half.max()) * 1e-6, 1e-12)
    logs = np.log(np.maximum(half, floor))
    best = logs[:2] - logs.mean()
    span = 3.0

    def scale2(a: np.ndarray) -> np.ndarray:
        # a: (g, 2) → (g,) squared scale for ratios e^(a1, a2, −a1−a2)
        full = np.column_stack([a, -a.sum(axis=1)])
        return (q @ np.exp(-2.0 * full).T).max(axis=0)

    for _ in range(levels):
        ticks = np.linspace(-span, span, grid)
        a1, a2 = np.meshgrid(best[0] + ticks, best[1] + ticks)
        cand = np.column_stack([a1.ravel(), a2.ravel()])
        best = cand[np.argmin(scale2(cand))]
        span /= 4.0
    ratios = np.exp(np.array([best[0], best[1], -best.sum()]))
    s = np.sqrt(scale2(best[None])[0]) * (1.0 + 1e-9)
    radii = np.maximum(s * ratios, floor)
    return EllipsoidGeometry(centre=c, radii=radii)


def part_triangles(tracer: SceneTracer, part: int) -> npt.NDArray[np.float64]:
    """(m, 3, 3) float64 world-space triangles of reflector part ``part``."""
    if not 0 <= part < len(tracer.part_names):
        raise ValueError(f"part {part} out of range 0..{len(tracer.part_names) - 1}")
    return tracer.positions[tracer.part == part]


def local_ellipsoid(tracer: SceneTracer, part: int) -> tuple[EllipsoidGeometry, np.ndarray]:
    """The local-layer EM geometry of a part and its EM origin (seed 003 §4, "Layered EMs").

    Returns
    -------
    geometry : EllipsoidGeometry
        :func:`min_volume_ellipsoid` of the part's vertices about the origin.
    origin : (3,) float64
        :func:`em_origin` of the part's triangles.
    """
    tri = part_triangles(tracer, part)
    origin = em_origin(tri)
    return min_volume_ellipsoid(tri.reshape(-1, 3), origin), origin


def _world_bounds(nodes) -> tuple[np.ndarray, np.ndarray] | None:
    pts = []
    for node in nodes:
        m = node.transform.matrix().astype(np.float64)
        pts.append(node.mesh.positions @ m[:3, :3].T + m[:3, 3])
    if not pts:
        return None
    allp = np.concatenate(pts)
    return allp.min(axis=0), allp.max(axis=0)


def distant_box(scene: Scene, margin: float = 0.0, far_scale: float = 10.0) -> BoxGeometry:
    """The distant layer's box map (seed 003 §4, "EM Representations").

    "For objects resting on flat surfaces, it is effective to align the box bottom
    with this flat surface": the room's own box when the scene has one.

    Parameters
    ----------
    scene
        The scene. Its room is every local node whose mesh is the ``room``
        primitive (``scene/primitives.box(inward=True)``).
    margin
        Without a room: relative padding of the box around the local objects and
        reflectors (its bottom stays on their lowest point, the floor).
    far_scale
        Without local objects: the cube's half edge as a multiple of the
        reflectors' bounding radius, centred on them.

    Returns
    -------
    BoxGeometry
    """
    rooms = [n for n in scene.local_objects() if n.mesh.name == "room"]
    if rooms:
        lo, hi = _world_bounds(rooms)
        return BoxGeometry(lo, hi)
    refl = _world_bounds(scene.reflectors())
    if refl is None:
        raise ValueError(f"scene {scene.name!r} has no reflector to bake")
    if scene.local_objects():
        lo, hi = _world_bounds(scene.local_objects() + scene.reflectors())
        pad = margin * (hi - lo)
        lo, hi = lo - pad, hi + pad
        lo[1] += pad[1]  # bottom on the floor
        return BoxGeometry(lo, hi)
    centre = (refl[0] + refl[1]) / 2
    half = far_scale * max(float(np.linalg.norm(refl[1] - refl[0])) / 2, 1e-6)
    return BoxGeometry(centre - half, centre + half)


# -- the rendering matrix ---------------------------------------------------------------


def cube_bilinear(
    vectors: npt.ArrayLike, size: int
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """Bilinear cube-map lookup weights (face clamped to edge).

    Parameters
    ----------
    vectors
        (k, 3) float lookup vectors (non-zero; need not be unit length).
    size
        Face edge n in texels.

    Returns
    -------
    texels : (k, 4) int64
        Flat texel indices f·n² + i·n + j into a (6, n, n) face array.
    weights : (k, 4) float64
        Bilinear weights; each row sums to 1.
    """
    face, uv = direction_to_uv(np.asarray(vectors, dtype=np.float64).reshape(-1, 3))
    x = uv[:, 0] * size - 0.5
    y = uv[:, 1] * size - 0.5
    j0, i0 = np.floor(x), np.floor(y)
    fx, fy = x - j0, y - i0
    j0, i0 = j0.astype(np.int64), i0.astype(np.int64)
    jj = np.clip(np.stack([j0, j0 + 1]), 0, size - 1)
    ii = np.clip(np.stack([i0, i0 + 1]), 0, size - 1)
    base = face * size * size
    texels = np.stack(
        [base + ii[a] * size + jj[b] for a in (0, 1) for b in (0, 1)],
        axis=1,
    )
    wx, wy = np.stack([1 - fx, fx]), np.stack([1 - fy, fy])
    weights = np.stack([wy[a] * wx[b] for a in (0, 1) for b in (0, 1)], axis=1)
    return texels, weights


def rendering_matrix(
    view: TracedView,
    part: int,
    geometry: BoxGeometry | EllipsoidGeometry,
    origin: npt.ArrayLike,
    size: int,
) -> tuple[sparse.csr_matrix, npt.NDArray[np.bool_]]:
    """The rendering matrix A of one part's layer (seed 003 §4, "EM Inference").

    Parameters
    ----------
    view
        A traced view with its per-sample rays (``ray_*`` attributes).
    part
        Reflector part index.
    geometry
        EM geometry the reflection rays are intersected with.
    origin
        (3,) EM origin; the lookup vector is exit point − origin.
    size
        Cube face edge n.

    Returns
    -------
    A : (R², 6n²) scipy.sparse.csr_matrix
        Row row·R + column is the pixel's mean, over its samples on the part, of
        the bilinear weights of their lookups; zero rows off the part. Samples
        whose ray misses the geometry contribute nothing (their row sums < 1).
    met : (R²,) bool
        Pixels on the part all of whose samples' rays meet the geometry: where
        the rows sum to 1.
    """
    if view.ray_pixel is None:
        raise ValueError("the view carries no per-sample rays; trace it with SceneTracer.trace")
    npix = view.size * view.size
    sel = view.ray_part == part
    pix = view.ray_pixel[sel]
    o = view.ray_point[sel].astype(np.float64)
    d = view.ray_direction[sel].astype(np.float64)
    t = geometry.exit_distance(o, d)
    vec = o + np.nan_to_num(t)[:, None] * d - np.asarray(origin, dtype=np.float64)
    ok = np.isfinite(t) & (np.linalg.norm(vec, axis=1) > 0)
    count = np.bincount(pix, minlength=npix).astype(np.float64)
    good = np.bincount(pix[ok], minlength=npix)
    texels, weights = cube_bilinear(vec[ok], size)
    weights = weights / count[pix[ok]][:, None]
    rows = np.repeat(pix[ok], 4)
    A = sparse.coo_matrix(
        (weights.ravel(), (rows, texels.ravel())), shape=(npix, 6 * size * size)
    ).tocsr()
    A.sum_duplicates()
    met = (count > 0) & (good == count)
    return A, met


def smoothness_operator(size: int) -> sparse.csr_matrix:
    """Texel differences x_i − x_j over neighbouring texels of a cube map, seams included.

    Each texel is paired with its neighbours one texel along s and along t; a
    neighbour past the face edge is found by extending the face plane and
    looking the direction up again, so the faces join.

    Parameters
    ----------
    size
        Cube face edge n.

    Returns
    -------
    (E, 6n²) scipy.sparse.csr_matrix
        One row +1/−1 per unordered neighbour pair.
    """
    n = size
    f, i, j = np.meshgrid(np.arange(6), np.arange(n), np.arange(n), indexing="ij")
    f, i, j = f.ravel(), i.ravel(), j.ravel()
    me = f * n * n + i * n + j
    pairs = []
    for di, dj in ((0, 1), (1, 0)):
        uv = np.stack([(j + dj + 0.5) / n, (i + di + 0.5) / n], axis=1)
        face, st = direction_to_uv(uv_to_direction(f, uv))
        jj = np.clip(np.floor(st[:, 0] * n).astype(np.int64), 0, n - 1)
        ii = np.clip(np.floor(st[:, 1] * n).astype(np.int64), 0, n - 1)
        other = face * n * n + ii * n + jj
        pairs.append(np.stack([me, other], axis=1))
    pr = np.concatenate(pairs)
    pr = np.unique(np.sort(pr[pr[:, 0] != pr[:, 1]], axis=1), axis=0)
    e = len(pr)
    rows = np.repeat(np.arange(e), 2)
    vals = np.tile([1.0, -1.0], e)
    return sparse.csr_matrix((vals, (rows, pr.ravel())), shape=(e, 6 * n * n))


# -- the solve --------------------------------------------------------------------------


def psnr(estimate: npt.ArrayLike, reference: npt.ArrayLike, peak: float | None = None) -> float:
    """10 log10(peak² / MSE) in dB; ``peak`` defaults to the reference's maximum."""
    x = np.asarray(estimate, dtype=np.float64)
    y = np.asarray(reference, dtype=np.float64)
    mse = float(np.mean((x - y) ** 2)) if y.size else 0.0
    peak = float(np.max(np.abs(y))) if peak is None and y.size else (peak or 1.0)
    if mse == 0.0:
        return float("inf")
    return 10.0 * np.log10(max(peak, 1e-300) ** 2 / mse)


@dataclass
class EMInference:
    """One inferred environment map (seed 003 §4, "EM Inference").

    Attributes
    ----------
    em : (6, n, n, C) float64
        The map in OpenGL face order (core/cubemap.py), clipped to ≥ 0.
    seen : (6, n, n) bool
        Texels that contribute to at least one pixel (column sums of A > 0).
    matrix : (R², 6n²) scipy.sparse.csr_matrix
        The rendering matrix A.
    pixels : (R², ) bool
        Rows fitted (pixels on the part).
    target : (k, C) float64
        b, the layer at those pixels.
    psnr : float
        PSNR of A x against b over the fitted pixels, dB (peak = max b).
    iterations : list of int
        CG iterations per channel.
    geometry : BoxGeometry or EllipsoidGeometry
    origin : (3,) float64
    seconds : float
        Wall time of matrix and solve.
    """

    em: np.ndarray
    seen: np.ndarray
    matrix: sparse.csr_matrix
    pixels: np.ndarray
    target: np.ndarray
    psnr: float
    iterations: list[int]
    geometry: BoxGeometry | EllipsoidGeometry
    origin: np.ndarray
    seconds: float = 0.0

    def render(self) -> np.ndarray:
        """(k, C) A x at the fitted pixels."""
        n = self.em.shape[1]
        return self.matrix[self.pixels] @ self.em.reshape(6 * n * n, -1)


def infer_em(
    view: TracedView,
    part: int,
    layer: npt.ArrayLike,
    geometry: BoxGeometry | EllipsoidGeometry,
    origin: npt.ArrayLike,
    size: int = 32,
    smoothness: float = 1e-3,
    rtol: float = 1e-10,
    maxiter: int = 5000,
    matrix: tuple[sparse.csr_matrix, np.ndarray] | None = None,
) -> EMInference:
    """Least-squares EM of one part's layer (seed 003 §4, "EM Inference").

    Solves (AᵀA + λ DᵀD) x = Aᵀ b per channel by Jacobi-preconditioned CG,
    A from :func:`rendering_matrix`, D from :func:`smoothness_operator`, then
    clips x to ≥ 0 (the range term).

    Parameters
    ----------
    view
        Traced view with per-sample rays.
    part
        Reflector part index.
    layer
        (R, R, C) float, the layer b to match (e.g. ``view.distant[part]``).
    geometry, origin
        EM geometry and (3,) EM origin.
    size
        Cube face edge n.
    smoothness
        λ, weight of the texel-difference term (A's rows sum to 1, so λ is
        relative to one pixel's squared error).
    rtol, maxiter
        CG stopping rule.
    matrix
        A precomputed ``rendering_matrix(view, part, geometry, origin, size)``.

    Returns
    -------
    EMInference
    """
    start = time.perf_counter()
    A, _ = matrix if matrix is not None else rendering_matrix(view, part, geometry, origin, size)
    b_img = np.asarray(layer, dtype=np.float64)
    if b_img.shape[:2] != (view.size, view.size):
        raise ValueError(f"layer shape {b_img.shape} does not match the view ({view.size}²)")
    b_all = b_img.reshape(view.size * view.size, -1)
    pixels = view.coverage[part].ravel() > 0
    Ap = A[pixels]
    b = b_all[pixels]
    if Ap.shape[0] == 0:
        raise ValueError(f"part {part} covers no pixel of the view")
    D = smoothness_operator(size)
    M = (Ap.T @ Ap + smoothness * (D.T @ D)).tocsr()
    diag = M.diagonal()
    inv = np.where(diag > 0, 1.0 / np.where(diag > 0, diag, 1.0), 1.0)
    precond = splinalg.LinearOperator(M.shape, matvec=lambda v: inv * v, dtype=np.float64)
    rhs = Ap.T @ b
    x = np.zeros((M.shape[0], b.shape[1]))
    iterations = []
    for c in range(b.shape[1]):
        count = [0]

        def tick(_xk, count=count):
            count[0] += 1

        x0 = np.full(M.shape[0], float(b[:, c].mean()))
        xc, info = splinalg.cg(
            M, rhs[:, c], x0=x0, rtol=rtol, atol=0.0, maxiter=maxiter, M=precond, callback=tick
        )
        if info < 0:
            raise RuntimeError(f"conjugate gradient broke down (info {info})")
        x[:, c] = xc
        iterations.append(count[0])
    x = np.maximum(x, 0.0)
    seen = np.asarray(Ap.sum(axis=0)).ravel() > 0
    result = EMInference(
        em=x.reshape(6, size, size, -1),
        seen=seen.reshape(6, size, size),
        matrix=A,
        pixels=pixels,
        target=b,
        psnr=0.0,
        iterations=iterations,
        geometry=geometry,
        origin=np.asarray(origin, dtype=np.float64),
    )
    result.psnr = psnr(result.render(), b)
    result.seconds = time.perf_counter() - start
    return result


def infer_distant(
    scene: Scene,
    tracer: SceneTracer,
    view: TracedView,
    part: int,
    size: int = 32,
    smoothness: float = 1e-3,
    **kw,
) -> EMInference:
    """The distant-layer box EM of one part (seed 003 §4, "Layered EMs", Figure 5).

    Geometry :func:`distant_box` of the scene, origin :func:`em_origin` of the
    part's triangles, layer b = ``view.distant[part]``; other keywords go to
    :func:`infer_em`.
    """
    origin = em_origin(part_triangles(tracer, part))
    return infer_em(
        view, part, view.distant[part], distant_box(scene), origin, size, smoothness, **kw
    )


# -- all MIP levels at once (seed 003 §4, "EM MIPMAPs") ------------------------------------


def mip_ties(size: int, levels: int | None = None) -> sparse.csr_matrix:
    """Coarse-to-decimated-fine differences of a MIP chain.

    One row per texel of levels k ≥ 1: x_k[f, i, j] − ¼ Σ_{a,b∈{0,1}}
    x_{k−1}[f, 2i + a, 2j + b], over the chain's concatenated unknowns
    (:func:`envstudio.methods.pem.bake.mip.level_offsets`). It ties a level nothing looks
    up to the box filter of the level below (and a fine level nothing looks up to
    the coarse one), so every level is defined; it is weak (μ) and does not make
    levels decimated copies of each other, which §4 finds they are not.

    Returns
    -------
    (Σ_{k≥1} 6 n_k², Σ_k 6 n_k²) scipy.sparse.csr_matrix
    """
    sizes = mip_sizes(size, levels)
    offsets = level_offsets(size, levels)
    rows, cols, vals = [], [], []
    start = 0
    for k in range(1, len(sizes)):
        n, fine = sizes[k], sizes[k - 1]
        f, i, j = (
            a.ravel() for a in np.meshgrid(np.arange(6), np.arange(n), np.arange(n), indexing="ij")
        )
        row = start + f * n * n + i * n + j
        rows.append(row)
        cols.append(offsets[k] + f * n * n + i * n + j)
        vals.append(np.ones(len(row)))
        for a in (0, 1):
            for b in (0, 1):
                rows.append(row)
                cols.append(offsets[k - 1] + f * fine * fine + (2 * i + a) * fine + 2 * j + b)
                vals.append(np.full(len(row), -0.25))
        start += 6 * n * n
    total = int(offsets[-1])
    if start == 0:
        return sparse.csr_matrix((0, total))
    return sparse.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(start, total)
    )


@lru_cache(maxsize=16)
def mip_regulariser(size: int, levels: int, smoothness: float, tie: float) -> sparse.csr_matrix:
    """λ DᵀD + μ TᵀT over a chain: D the seam-crossing smoothness per level
    (:func:`smoothness_operator`, block diagonal), T :func:`mip_ties` (cached)."""
    blocks = [smoothness_operator(n) for n in mip_sizes(size, levels)]
    D = sparse.block_diag(blocks, format="csr")
    T = mip_ties(size, levels)
    return (smoothness * (D.T @ D) + tie * (T.T @ T)).tocsr()


#: The finest face edge from which :func:`solve_mip` preconditions with :class:`ChainMultigrid`
#: (studies/pem-paper-scale/README.md: at 64² its cycle costs more than the iterations it
#: saves); below it, Jacobi, the bits of before.
MULTIGRID_SIZE = 128


def _aggregation(sizes: list[int]) -> tuple[sparse.csr_matrix, list[int]]:
    """The 2 × 2 aggregation of every level of a chain, and the coarse chain's face edges.

    Texel (f, i, j) of a level of edge n > 1 joins aggregate (f, ⌊i/2⌋, ⌊j/2⌋) of edge
    ⌈n/2⌉; a level of edge 1 is kept. Same layout as :func:`mip_ties` (levels
    concatenated, faces of n² texels row by row).

    Returns
    -------
    P : (Σ_k 6 n_k², Σ_k 6 m_k²) scipy.sparse.csr_matrix
        Ones: the coarse chain prolonged piecewise constant.
    coarse : list of int
        The m_k.
    """
    cols, coarse, start = [], [], 0
    for n in sizes:
        m = (n + 1) // 2
        f, i, j = (
            a.ravel() for a in np.meshgrid(np.arange(6), np.arange(n), np.arange(n), indexing="ij")
        )
        cols.append(start + f * m * m + (i // 2) * m + j // 2)
        coarse.append(m)
        start += 6 * m * m
    cols = np.concatenate(cols)
    P = sparse.csr_matrix(
        (np.ones(len(cols)), cols, np.arange(len(cols) + 1)), shape=(len(cols), start)
    )
    return P, coarse


class ChainMultigrid:
    """A multigrid preconditioner for a MIP chain's normal matrix (not in seed 003).

    The regulariser λ DᵀD + μ TᵀT of :func:`solve_mip` is a Laplacian over 6 n² texels,
    so Jacobi-preconditioned CG needs O(n) iterations to fill the texels nothing looks
    up (measured: 600–1500 at n = 256, rtol 10⁻⁶). This is one symmetric V(1,1)
    cycle over :func:`_aggregation`'s hierarchy: operators M_{l+1} = P_lᵀ M_l P_l
    (Galerkin), smoothing x ← x + S_l (r − M_l x) with S_l = ω diag(Σ_j |M_l,ij|)⁻¹
    (ℓ1 Jacobi) once before and once after the coarse correction, and the coarsest
    chain (≤ ``coarsest`` texels, or every level of edge 1) solved exactly (dense
    Cholesky). ω < 2 keeps the cycle symmetric positive definite, as CG needs:
    2 S⁻¹ − M = (2/ω − 1) diag(Σ_j |M_ij|) + (diag(Σ_j |M_ij|) − M), a positive diagonal
    plus a diagonally dominant matrix. An aggregation hierarchy, not the chain's own
    levels: those are unknowns of the one solve, not coarse versions of each other.

    Parameters
    ----------
    M
        (N, N) the symmetric positive definite normal matrix, N = Σ_k 6 n_k².
    sizes
        The chain's face edges n_k (:func:`~envstudio.methods.pem.bake.mip.mip_sizes`).
    weight
        ω of the smoothing.
    coarsest
        Unknowns below which the hierarchy stops.
    """

    def __init__(
        self, M: sparse.spmatrix, sizes: list[int], weight: float = 1.5, coarsest: int = 600
    ):
        M = sparse.csr_matrix(M)
        self.operators, self.smoothers, self.prolongations = [], [], []
        while True:
            self.operators.append(M)
            self.smoothers.append(weight / np.asarray(abs(M).sum(axis=1)).ravel())
            if M.shape[0] <= coarsest or max(sizes) == 1:
                break
            P, sizes = _aggregation(sizes)
            self.prolongations.append(P)
            M = (P.T @ M @ P).tocsr()
        self.coarse = sla.cho_factor(M.toarray())

    def __call__(self, r: np.ndarray) -> np.ndarray:
        """(N,) B r, B ≈ M⁻¹ symmetric positive definite: one V-cycle from zero."""
        return self._cycle(np.asarray(r, dtype=np.float64), 0)

    def _cycle(self, r: np.ndarray, level: int) -> np.ndarray:
        if level == len(self.prolongations):
            return sla.cho_solve(self.coarse, r)
        M, s, P = self.operators[level], self.smoothers[level], self.prolongations[level]
        x = s * r
        x += P @ self._cycle(P.T @ (r - M @ x), level + 1)
        x += s * (r - M @ x)
        return x


def bounded_cg(
    M: sparse.csr_matrix,
    rhs: npt.ArrayLike,
    x0: npt.ArrayLike,
    lo: npt.ArrayLike,
    hi: npt.ArrayLike,
    rtol: float = 1e-6,
    maxiter: int = 3000,
    active_rounds: int = 2,
    preconditioner: ChainMultigrid | None = None,
) -> tuple[np.ndarray, int]:
    """Solve M x = rhs (M symmetric positive semi-definite) with lo ≤ x ≤ hi by an active set.

    Preconditioned CG; the entries a solve puts out of range are fixed at the
    bound and the others re-solved, warm started, at most ``active_rounds``
    times; the result is clipped. ``lo`` and ``hi`` are scalars or per entry.
    Each round stops at ||r|| ≤ rtol ||b|| of its free system (scipy's rule).
    BLAS runs on one thread meanwhile: CG's many short dot products are ten
    times slower when BLAS threads contend for loaded cores (measured here:
    30 s against 3 s for one 256² view).

    Parameters
    ----------
    preconditioner
        B ≈ M⁻¹ on (N,) vectors, symmetric positive definite (:class:`ChainMultigrid`);
        a round with entries fixed uses B restricted to its free entries. None:
        Jacobi, diag(M)⁻¹.

    Returns
    -------
    x : (N,) float64
    iterations : int
        CG iterations, all rounds.
    """
    n = M.shape[0]
    lo = np.broadcast_to(np.asarray(lo, dtype=np.float64), n)
    hi = np.broadcast_to(np.asarray(hi, dtype=np.float64), n)
    if preconditioner is None:
        diag = M.diagonal()
        inv = np.where(diag > 0, 1.0 / np.where(diag > 0, diag, 1.0), 1.0)
        preconditioner = inv.__mul__
    x = np.clip(np.asarray(x0, dtype=np.float64), lo, hi)
    rhs = np.asarray(rhs, dtype=np.float64)
    fixed = np.zeros(n, bool)
    count = [0]

    def tick(_xk):
        count[0] += 1

    with threadpool_limits(1):  # CG's dot products: BLAS threads only contend here
        for _ in range(active_rounds + 1):
            x, fixed, done = _bounded_round(
                M, rhs, x, fixed, preconditioner, lo, hi, rtol, maxiter, tick
            )
            if done:
                break
    return x, count[0]


def _bounded_round(M, rhs, x, fixed, preconditioner, lo, hi, rtol, maxiter, tick):
    """One active-set round of :func:`bounded_cg`: (x, fixed, nothing left out of range)."""
    free = np.flatnonzero(~fixed)
    rows = M[free]
    Mf = rows[:, free]
    rf = rhs[free] - rows[:, np.flatnonzero(fixed)] @ x[fixed]

    def restricted(v):  # B on the free entries: S B Sᵀ, still symmetric positive definite
        if len(free) == len(x):
            return preconditioner(v)
        full = np.zeros(len(x))
        full[free] = v
        return preconditioner(full)[free]

    pre = splinalg.LinearOperator(Mf.shape, matvec=restricted, dtype=np.float64)
    sol, info = splinalg.cg(
        Mf, rf, x0=x[free], rtol=rtol, atol=0.0, maxiter=maxiter, M=pre, callback=tick
    )
    if info < 0:
        raise RuntimeError(f"conjugate gradient broke down (info {info})")
    x[free] = sol
    out_of_range = (x < lo) | (x > hi)
    x = np.clip(x, lo, hi)
    return x, fixed | out_of_range, not out_of_range[free].any()


def solve_mip(
    A: sparse.spmatrix,
    b: npt.ArrayLike,
    size: int,
    levels: int | None = None,
    smoothness: float = 1e-3,
    tie: float = 1e-3,
    lo: npt.ArrayLike = 0.0,
    hi: npt.ArrayLike = np.inf,
    rtol: float = 1e-6,
    maxiter: int = 3000,
    active_rounds: int = 2,
    anchor: npt.ArrayLike | None = None,
    coupling: float = 0.0,
) -> tuple[list[np.ndarray], list[int]]:
    """Every MIP level of an EM from one least-squares solve (seed 003 §4, "EM MIPMAPs").

    Solves (AᵀA + λ DᵀD + μ TᵀT) x = Aᵀ b per channel by Jacobi-preconditioned
    conjugate gradient, x the concatenated levels. The range terms (RGB ≥ 0,
    alpha in [0, 1]) are bounds kept by an active set: texels a solve puts out
    of [lo, hi] are fixed at the bound and the others re-solved, warm started,
    for at most ``active_rounds`` rounds, then a final clip. (A plain clip after
    one solve costs 2–6 dB on ``room``: unbounded, the levels trade positive
    texels against negative ones.)

    Parameters
    ----------
    A
        (m, Σ_k 6 n_k²) rendering matrix of the fitted pixels
        (:func:`envstudio.methods.pem.bake.lookups.trilinear_matrix`).
    b
        (m, C) the layer at those pixels.
    size, levels
        n and L of the chain (L default: the full chain).
    smoothness, tie
        λ and μ (:func:`mip_regulariser`); A's rows sum to 1, so both are relative to
        one pixel's squared error.
    lo, hi
        Range per channel: scalars or (C,).
    rtol, maxiter
        CG stopping rule (per round).
    active_rounds
        Re-solves with the out-of-range texels fixed (0: one solve and a clip).
    anchor
        (Σ_k 6 n_k², C) maps the solution is drawn towards (coupled inference, module
        docstring; not in seed 003): the neighbouring views' mean, levels concatenated.
    coupling
        Weight c of c ||x − anchor||² (γ |N(v)|); 0 (default) leaves the solve exactly
        as without it. Relative to one pixel's squared error, as λ and μ.

    Returns
    -------
    levels : list of (6, n_k, n_k, C) float64
    iterations : list of int
        CG iterations per channel, all rounds.
    """
    sizes = mip_sizes(size, levels)
    offsets = level_offsets(size, len(sizes))
    b = np.asarray(b, dtype=np.float64)
    b = b.reshape(len(b), -1)
    if A.shape != (len(b), offsets[-1]):
        raise ValueError(f"A is {A.shape}, expected ({len(b)}, {offsets[-1]}) for this chain")
    if len(b) == 0:
        raise ValueError("no pixel to fit")
    A = sparse.csr_matrix(A)
    M = (A.T @ A + mip_regulariser(size, len(sizes), float(smoothness), float(tie))).tocsr()
    rhs = A.T @ b
    if coupling:  # γ = 0 adds nothing at all: the independent solve, bit for bit
        if anchor is None:
            raise ValueError("a coupled solve needs the anchor maps")
        anchor = np.asarray(anchor, dtype=np.float64).reshape(M.shape[0], -1)
        if anchor.shape[1] != b.shape[1]:
            raise ValueError(f"anchor has {anchor.shape[1]} channels, b has {b.shape[1]}")
        M = (M + float(coupling) * sparse.identity(M.shape[0], format="csr")).tocsr()
        rhs = rhs + float(coupling) * anchor
    x = np.zeros((M.shape[0], b.shape[1]))
    lo = np.broadcast_to(np.asarray(lo, dtype=np.float64), b.shape[1])
    hi = np.broadcast_to(np.asarray(hi, dtype=np.float64), b.shape[1])
    iterations = []
    multigrid = None  # Jacobi below MULTIGRID_SIZE, where the cycle costs more than it saves
    if size >= MULTIGRID_SIZE:
        with threadpool_limits(1):  # one hierarchy for every channel and round
            multigrid = ChainMultigrid(M, sizes)
    for c in range(b.shape[1]):
        start = np.full(M.shape[0], float(np.clip(b[:, c].mean(), lo[c], hi[c])))
        x[:, c], count = bounded_cg(
            M, rhs[:, c], start, lo[c], hi[c], rtol, maxiter, active_rounds, multigrid
        )
        iterations.append(count)
    out = [x[offsets[k] : offsets[k + 1]].reshape(6, n, n, -1) for k, n in enumerate(sizes)]
    return out, iterations


@dataclass
class MipInference:
    """An EM's inferred MIP chain for one part and model (seed 003 §4, "EM MIPMAPs").

    Attributes
    ----------
    levels : list of (6, n_k, n_k, C) float64
        Level k has edge n >> k, OpenGL face order (core/cubemap.py).
    matrix : (R², Σ_k 6 n_k²) scipy.sparse.csr_matrix
        The trilinear rendering matrix of every pixel of the part (``PixelLookups.matrix``).
    pixels : (R²,) bool
        The fitted pixels.
    target : (k, C) float64
        b at those pixels.
    psnr : float
        A x against b over the fitted pixels, dB (peak = max b).
    iterations : list of int
        CG iterations per channel.
    seconds : float
        Wall time of the solve.
    """

    levels: list[np.ndarray]
    matrix: sparse.csr_matrix
    pixels: np.ndarray
    target: np.ndarray
    psnr: float = 0.0
    iterations: list[int] = field(default_factory=list)
    seconds: float = 0.0

    def flat(self) -> np.ndarray:
        """(Σ_k 6 n_k², C) the concatenated levels, as the matrix's columns order them."""
        return np.concatenate([lv.reshape(-1, lv.shape[-1]) for lv in self.levels])

    def render(self) -> np.ndarray:
        """(R², C) A x for every row of the matrix (0 off the part's pixels)."""
        return self.matrix @ self.flat()


def infer_mip(
    A: sparse.spmatrix,
    pixels: npt.ArrayLike,
    layer: npt.ArrayLike,
    size: int,
    levels: int | None = None,
    smoothness: float = 1e-3,
    tie: float = 1e-3,
    lo: npt.ArrayLike = 0.0,
    hi: npt.ArrayLike = np.inf,
    **kw,
) -> MipInference:
    """Infer a MIP chain so that A x matches ``layer`` on ``pixels`` (:func:`solve_mip`).

    Parameters
    ----------
    A
        (R², Σ 6 n_k²) trilinear rendering matrix of all pixels.
    pixels
        (R²,) or (R, R) bool, the pixels to fit.
    layer
        (R, R, C) or (R², C) float, b.
    size, levels, smoothness, tie, lo, hi
        As :func:`solve_mip`; other keywords go to it too.

    Returns
    -------
    MipInference
    """
    start = time.perf_counter()
    A = sparse.csr_matrix(A)
    pixels = np.asarray(pixels, dtype=bool).ravel()
    b_all = np.asarray(layer, dtype=np.float64)
    b_all = b_all.reshape(len(pixels), -1)
    b = b_all[pixels]
    if len(b) == 0:
        raise ValueError("no pixel to fit")
    lv, iterations = solve_mip(A[pixels], b, size, levels, smoothness, tie, lo, hi, **kw)
    result = MipInference(lv, A, pixels, b, iterations=iterations)
    result.psnr = psnr(result.render()[pixels], b)
    result.seconds = time.perf_counter() - start
    return result


def infer_local_over(
    A: sparse.spmatrix,
    pixels: npt.ArrayLike,
    incident: npt.ArrayLike,
    distant: npt.ArrayLike,
    alpha: npt.ArrayLike,
    size: int,
    levels: int | None = None,
    smoothness: float = 1e-3,
    tie: float = 1e-3,
    **kw,
) -> MipInference:
    """The local layer's premultiplied RGBA chain, fitted through the "over" (seed 003 §4).

    The playback composites I = rgb_L + (1 − α_L)·I_D, I_D = A_D x_D the distant
    chain's lookup (inferred first). Two linear solves (:func:`solve_mip`):

    1. α: A x_α ≈ α_L, the traced local coverage, in [0, 1];
    2. rgb: A x_c ≈ I_c − (1 − A x_α)·I_D,c per channel, ≥ 0,

    so the colour makes up for what the fitted α and the fitted distant layer
    miss of the traced I. With α and D exact the rgb target is α_L·L, the
    premultiplied b = (α_L·L, α_L) of the brief.

    Parameters
    ----------
    A
        (R², Σ 6 n_k²) trilinear matrix of the local model.
    pixels
        (R²,) bool fitted pixels.
    incident, distant
        (R², 3) the traced I and I_D at every pixel.
    alpha
        (R²,) the traced α_L (0 on convex-hull pixels).
    size, levels, smoothness, tie
        As :func:`solve_mip`; other keywords go to it too (``anchor``, (N, 4): its
        rgb to the colour solve, its α to the α solve).

    Returns
    -------
    MipInference
        ``target`` (k, 4): the rgb targets of step 2 and α_L; ``psnr`` that of the
        composite I = rgb + (1 − α)·I_D against the traced I over the pixels.
    """
    start = time.perf_counter()
    A = sparse.csr_matrix(A)
    pixels = np.asarray(pixels, bool).ravel()
    Ap = A[pixels]
    if Ap.shape[0] == 0:
        raise ValueError("no pixel to fit")
    inc = np.asarray(incident, np.float64).reshape(-1, 3)[pixels]
    dist = np.asarray(distant, np.float64).reshape(-1, 3)[pixels]
    a = np.asarray(alpha, np.float64).ravel()[pixels]
    anchor = kw.pop("anchor", None)  # (N, 4): rgb for the colour solve, α for the α solve
    if anchor is not None:
        anchor = np.asarray(anchor, np.float64).reshape(-1, 4)
        kw_a, kw_rgb = {**kw, "anchor": anchor[:, 3:]}, {**kw, "anchor": anchor[:, :3]}
    else:
        kw_a = kw_rgb = kw
    x_a, it_a = solve_mip(Ap, a[:, None], size, levels, smoothness, tie, 0.0, 1.0, **kw_a)
    flat_a = np.concatenate([lv.reshape(-1, 1) for lv in x_a])
    a_hat = (Ap @ flat_a)[:, 0]
    rgb_target = inc - (1.0 - a_hat)[:, None] * dist
    x_rgb, it_rgb = solve_mip(Ap, rgb_target, size, levels, smoothness, tie, 0.0, np.inf, **kw_rgb)
    chain = [np.concatenate([c, al], axis=-1) for c, al in zip(x_rgb, x_a, strict=True)]
    result = MipInference(
        chain, A, pixels, np.column_stack([rgb_target, a]), iterations=it_rgb + it_a
    )
    loc = result.render()[pixels]
    result.psnr = psnr(loc[:, :3] + (1.0 - loc[:, 3:]) * dist, inc)
    result.seconds = time.perf_counter() - start
    return result
