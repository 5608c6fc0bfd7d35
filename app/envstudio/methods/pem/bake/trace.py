"""Segmented ray tracing of one view for a PEM bake (seed 003 §3, §4 "Layered EMs", Figure 4).

Embree (through embreex) intersects the scene's world-space triangles, vectorised
over all rays of a view: R × R pixels with ``samples`` jittered rays each.

What a primary ray returns
--------------------------
- It misses: the environment's radiance along it (bilinear lat-long lookup).
- It hits a local object: albedo/π · E_sh9(n), the SH9 irradiance of the
  environment along the shading normal turned towards the ray, as the frame and
  shaders/reference/paths.glsl draw local diffuse objects.
- It hits a reflector part p at a point with shading normal n (turned towards
  the viewer, as common/eq8.glsl does), view direction v and mirror direction
  r = reflect(−v, n). The sample then records, for part p (Figure 4):

  * diffuse  d = k_d/π · E_sh9(n), the diffuse radiance of eq. 8 of seed 000
    (unweighted by Fresnel, unshadowed, as the playback draws it);
  * Fresnel  F = f_λ + (1 − f_λ)(1 − r·n)^5, clamped as shaders/common/fresnel.glsl, per
    RGB channel in the radiance; the layer stored is its mean over the channels (the
    playback applies its own f_λ, a colour);
  * distant  D: the ray along r traced through local objects only. The reflector
    parts are transparent to it ("the ray tracer propagates rays through the
    reflecting object if they intersect after the first bounce", §4), so D is
    defined for every sample of the part;
  * local    the ray along r traced through everything: when its first hit is a
    reflector (any part), the sample is local (alpha 1) with colour the radiance
    of that hit — the same eq. 8 shading, continuing along mirror directions for
    at most :data:`TRACE_BOUNCES` traces after the first hit, then black, as
    paths.glsl bounds its paths. Otherwise the sample is not local (alpha 0) and
    what it sees is D.

  and its ground-truth radiance (1 − F)·d + F·I with I the radiance along r.

Composition (Figure 4 and §4 "Layered EMs")
-------------------------------------------
Per pixel of part p, with α_L the local alpha, L the local colour, D the distant
layer, F the Fresnel layer and d the diffuse layer::

    incident  I = α_L·L + (1 − α_L)·D                 (the "over" of §4)
    part      C_p = (1 − F)·d + F·I                   (seed 000 eq. 8, common/eq8.glsl)
    composite C = B + Σ_p c_p·C_p

where c_p is the fraction of the pixel's samples that hit part p and B the
background (samples hitting local objects or nothing, divided by the sample
count). The paper writes the reflector as ``diffuse + (α_L rgb_L + (1 − α_L)
rgb_D)·F``: the same, its diffuse layer being (1 − F)·d, which
:meth:`TracedView.diffuse_term` returns. With one sample per pixel the
recombination is exact; with several it is exact up to the variation of F, d,
D within a pixel (layers are per-pixel means: D and F over the part's samples,
L over its local samples).

Glossy reflectors (issue 31 part 5; seed 003 §7: "handling glossy surfaces as
well as mirror-like ones should be possible with our techniques but remains to
be investigated")
------------------------------------------------------------------------------
By default (``phong_exponent`` None or 0) reflectors are traced as perfect
mirrors, the paper's teapot. With a Phong exponent N > 0 every reflector sample
(each of a pixel's rays on its own) draws one direction l from the normalised
Phong lobe about its mirror direction r, the lobe of the reference
(shaders/common/sampling.glsl ``sample_phong``, seed 000 eq. 7)::

    p(l) = (N + 1)/(2π) · max(r·l, 0)^N,   cos θ = (1 − ξ₁)^(1/(N+1)),  φ = 2π ξ₂

about r, so that the mean of the radiance along the l's estimates
P = (N + 1)/(2π) ∫ L(l) max(r·l, 0)^N dl, which the reference weights by the
same F = Schlick(n·v). A direction below the surface (below the shading
normal's plane or the triangle's own, as shaders/reference/paths.glsl) is
rejected: it carries no light (radiance 0, not local, distant 0) and still
counts in the pixel's mean, as the traced reference counts it; it is not folded
back above the surface. The local/distant split is then made per sample along l
exactly as along r for a mirror, and a path that meets a reflector again
continues along a lobe sample of its own (the reference's paths do the same),
up to :data:`TRACE_BOUNCES` traces. The lobe draws come from their own stream
(seed ``[seed, LOBE_STREAM]``), so the pixel jitter is the mirror trace's.
What the inference intersects with the EM geometry (``ray_direction``) stays
the mirror direction r, the playback's lookup: the inferred maps are per-view
maps of the lobe-averaged incident radiance, read by the playback's trilinear
lookups along r. Not in the paper.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from embreex import mesh_construction, rtcore_scene

from envstudio.core.fresnel import schlick
from envstudio.core.resample import sample_latlong
from envstudio.core.sh import irradiance_sh9, project_latlong_sh9
from envstudio.core.transforms import normal_matrix
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.graph import Scene

#: Traces after the first reflector hit before a path returns black
#: (methods/reference/tracing.py TRACE_BOUNCES, shaders/reference/paths.glsl).
TRACE_BOUNCES = 3

#: Second word of the lobe draws' seed ``[seed, LOBE_STREAM]`` (module docstring).
LOBE_STREAM = 31


def sample_phong(r, exponent: float, xi):
    """Directions drawn from the normalised Phong lobe (N + 1)/(2π) max(r·l, 0)^N about r.

    The reference's sampler (shaders/common/sampling.glsl ``sample_phong`` and
    ``frame_around``): cos θ = (1 − ξ₁)^(1/(N+1)), φ = 2π ξ₂ about r.

    Parameters
    ----------
    r
        (n, 3) float unit lobe axes (mirror directions).
    exponent
        N > 0.
    xi
        (n, 2) float uniform numbers in [0, 1).

    Returns
    -------
    (n, 3) float64
        Unit directions.
    """
    r = np.asarray(r, dtype=np.float64).reshape(-1, 3)
    xi = np.asarray(xi, dtype=np.float64).reshape(-1, 2)
    c = np.power(1.0 - xi[:, 0], 1.0 / (float(exponent) + 1.0))
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    phi = 2.0 * np.pi * xi[:, 1]
    helper = np.zeros_like(r)
    near_y = np.abs(r[:, 1]) >= 0.999
    helper[~near_y, 1] = 1.0
    helper[near_y, 0] = 1.0
    t = np.cross(helper, r)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    b = np.cross(r, t)
    return (s * np.cos(phi))[:, None] * t + (s * np.sin(phi))[:, None] * b + c[:, None] * r


@dataclass
class TracedView:
    """Segmented layers of one view (seed 003 Figure 4).

    Attributes
    ----------
    camera : OrbitCamera
        The view.
    size : int
        R; images are R × R, row 0 at the top.
    samples : int
        Rays per pixel.
    part_names : list of str
        The P reflector parts (reflector nodes of the scene), in scene order.
    composite : (R, R, 3) float32
        Ground truth: mean radiance of each pixel's samples.
    background : (R, R, 3) float32
        Sum of the radiance of samples not hitting a reflector, over ``samples``.
    coverage : (P, R, R) float32
        Fraction of each pixel's samples that hit the part.
    diffuse : (P, R, R, 3) float32
        Diffuse layer d = k_d/π · E_sh9(n), mean over the part's samples.
    fresnel : (P, R, R) float32
        Fresnel modulation layer F (Schlick, the mean of its RGB channels), mean over the
        part's samples.
    distant : (P, R, R, 3) float32
        Distant layer D (reflector transparent after the first bounce), mean over the
        part's samples; defined wherever coverage > 0.
    local_rgb : (P, R, R, 3) float32
        Local colour layer L, mean over the part's local samples (0 where none).
    local_alpha : (P, R, R) float32
        Local coverage α_L: fraction of the part's samples whose reflection hits a
        reflector.
    seconds : float
        Wall time of the trace.
    ray_pixel : (k,) int64, optional
        For each of the k samples that hit a reflector, its pixel row·R + column.
    ray_part : (k,) int64, optional
        The part each such sample hit.
    ray_point : (k, 3) float32, optional
        Its hit point (world space, offset along the normal as the tracer
        continues the ray from it).
    ray_normal : (k, 3) float32, optional
        Its unit shading normal, turned towards the viewer.
    ray_direction : (k, 3) float32, optional
        Its unit reflection direction r = reflect(−v, n): what EM inference
        intersects with the EM geometry (seed 003 §4, "EM Representations"); the
        mirror direction also when the lobe is sampled (the playback's lookup).
    phong_exponent : float
        N of the sampled Phong lobe about r; 0: a mirror (module docstring).
    """

    camera: OrbitCamera
    size: int
    samples: int
    part_names: list[str]
    composite: npt.NDArray[np.float32]
    background: npt.NDArray[np.float32]
    coverage: npt.NDArray[np.float32]
    diffuse: npt.NDArray[np.float32]
    fresnel: npt.NDArray[np.float32]
    distant: npt.NDArray[np.float32]
    local_rgb: npt.NDArray[np.float32]
    local_alpha: npt.NDArray[np.float32]
    seconds: float = 0.0
    ray_pixel: npt.NDArray[np.int64] | None = None
    ray_part: npt.NDArray[np.int64] | None = None
    ray_point: npt.NDArray[np.float32] | None = None
    ray_normal: npt.NDArray[np.float32] | None = None
    ray_direction: npt.NDArray[np.float32] | None = None
    phong_exponent: float = 0.0

    def incident(self) -> npt.NDArray[np.float64]:
        """(P, R, R, 3) incident specular layer α_L·L + (1 − α_L)·D (local over distant)."""
        a = self.local_alpha[..., None].astype(np.float64)
        return a * self.local_rgb + (1.0 - a) * self.distant

    def halved(self) -> TracedView:
        """The view at R // 2: each pixel the 2 × 2 box of this one's (an odd edge drops its last).

        Means are taken so that the layers still compose exactly: α_L and coverage are
        the means; L is the mean of α_L·L over the mean α_L; D is the mean of
        (1 − α_L)·D over 1 − mean α_L (the plain mean where nothing is local). So
        :meth:`incident` is the mean of the four incident values, and the premultiplied
        α_L·L and the distant layer that shows through are the four pixels' means. The
        per-sample ray arrays are dropped. Used by the bake's coarser footprints
        (methods/pem/bake/models.py).

        Raises
        ------
        ValueError
            An image of fewer than 2 × 2 pixels.
        """
        half = self.size // 2
        if half < 1:
            raise ValueError(f"cannot halve a {self.size}² view")

        def box(a, first=1):
            """2 × 2 means over axes ``first`` and ``first`` + 1 (the image's rows, columns)."""
            a = np.moveaxis(np.asarray(a, np.float64), (first, first + 1), (0, 1))
            a = a[: 2 * half, : 2 * half]
            a = 0.25 * (a[0::2, 0::2] + a[1::2, 0::2] + a[0::2, 1::2] + a[1::2, 1::2])
            return np.moveaxis(a, (0, 1), (first, first + 1))

        alpha = self.local_alpha.astype(np.float64)
        a_mean = box(alpha)
        local = box(alpha[..., None] * self.local_rgb)
        shown = box((1.0 - alpha[..., None]) * self.distant)
        open_part = (1.0 - a_mean)[..., None]
        distant = np.where(open_part > 1e-6, shown / np.maximum(open_part, 1e-6), box(self.distant))
        rgb = np.where(a_mean[..., None] > 0, local / np.maximum(a_mean[..., None], 1e-12), 0.0)
        f32 = np.float32
        return TracedView(
            camera=self.camera,
            size=half,
            samples=4 * self.samples,
            part_names=list(self.part_names),
            composite=box(self.composite, 0).astype(f32),
            background=box(self.background, 0).astype(f32),
            coverage=box(self.coverage).astype(f32),
            diffuse=box(self.diffuse).astype(f32),
            fresnel=box(self.fresnel).astype(f32),
            distant=distant.astype(f32),
            local_rgb=rgb.astype(f32),
            local_alpha=a_mean.astype(f32),
            phong_exponent=self.phong_exponent,
        )

    def diffuse_term(self) -> npt.NDArray[np.float64]:
        """(P, R, R, 3) the paper's additive diffuse layer, (1 − F)·d."""
        return (1.0 - self.fresnel[..., None].astype(np.float64)) * self.diffuse

    def part_images(self) -> npt.NDArray[np.float64]:
        """(P, R, R, 3) C_p = (1 − F)·d + F·(α_L·L + (1 − α_L)·D) per part."""
        return self.diffuse_term() + self.fresnel[..., None] * self.incident()

    def recombine(self) -> npt.NDArray[np.float64]:
        """(R, R, 3) B + Σ_p c_p·C_p: the composite rebuilt from the layers (module docstring)."""
        return self.background + np.einsum("pij,pijc->ijc", self.coverage, self.part_images())


def camera_rays(camera: OrbitCamera, size: int, col, row):
    """Camera rays through image points (col, row) of an R × R image (row 0 at the top).

    Parameters
    ----------
    camera
        Pinhole camera (``fov_y``, aspect 1).
    size
        R.
    col, row
        (k,) float image coordinates in pixels; a pixel's centre is at + 0.5.

    Returns
    -------
    origins, directions : (k, 3) float64
        The camera position, and unit directions.
    """
    col, row = np.asarray(col, dtype=np.float64), np.asarray(row, dtype=np.float64)
    view = camera.view_matrix().astype(np.float64)
    side, up, back = view[0, :3], view[1, :3], view[2, :3]
    half = np.tan(np.radians(camera.fov_y) / 2.0)
    x = (col / size * 2.0 - 1.0) * half
    y = (1.0 - row / size * 2.0) * half
    d = x[:, None] * side + y[:, None] * up - back
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.broadcast_to(camera.position, d.shape).astype(np.float64), d


class SceneTracer:
    """A scene's triangles in Embree, ready to trace views (GL-free).

    Parameters
    ----------
    scene
        Reflector nodes become parts (in order); local nodes are diffuse with their
        ``color`` as albedo; the environment is the far field and, projected to SH9,
        lights every diffuse term.
    bounces
        Traces after the first reflector hit before a path returns black.

    Raises
    ------
    ValueError
        A scene without a reflector.
    """

    def __init__(self, scene: Scene, bounces: int = TRACE_BOUNCES):
        reflectors = scene.reflectors()
        if not reflectors:
            raise ValueError(f"scene {scene.name!r} has no reflector to bake")
        self.part_names = [n.name for n in reflectors]
        self.bounces = int(bounces)
        self.environment = np.asarray(scene.environment.radiance, dtype=np.float32)
        self.sh9 = project_latlong_sh9(self.environment)
        self.kd = np.array([n.material.kd for n in reflectors], dtype=np.float64)
        self.f0 = np.array(  # (P, 3): f_λ per RGB channel
            [np.broadcast_to(np.asarray(n.material.fresnel, float), (3,)) for n in reflectors]
        )
        positions, normals, part, albedo = [], [], [], []
        index = {id(n): i for i, n in enumerate(reflectors)}
        for node in scene.nodes:
            mesh, model = node.mesh, node.transform.matrix().astype(np.float64)
            world = mesh.positions @ model[:3, :3].T + model[:3, 3]
            nrm = mesh.normals @ normal_matrix(model).astype(np.float64).T
            nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
            positions.append(world[mesh.indices])
            normals.append(nrm[mesh.indices])
            m = mesh.triangle_count
            part.append(np.full(m, index.get(id(node), -1), dtype=np.int64))
            albedo.append(np.broadcast_to(np.asarray(node.color, dtype=np.float64), (m, 3)))
        #: (m, 3, 3) float64 world-space triangle corners.
        self.positions = np.concatenate(positions)
        #: (m, 3, 3) float64 unit corner normals.
        self.normals = np.concatenate(normals)
        #: (m,) int64 reflector part of each triangle, −1 for local objects.
        self.part = np.concatenate(part)
        #: (P,) int64 index of each part's first triangle: a part's triangles are
        #: contiguous, in the order of its node's mesh faces.
        self.part_start = np.array(
            [np.flatnonzero(self.part == p)[0] for p in range(len(reflectors))], dtype=np.int64
        )
        #: (m, 3) float64 albedo of local triangles.
        self.albedo = np.concatenate(albedo)
        extent = np.ptp(self.positions.reshape(-1, 3), axis=0)
        self.ray_offset = float(1e-4 * np.linalg.norm(extent))
        self._all = self._embree(np.arange(len(self.part)))
        self._local_ids = np.flatnonzero(self.part < 0)
        self._local = self._embree(self._local_ids) if len(self._local_ids) else None

    def _embree(self, ids: npt.NDArray[np.int64]) -> rtcore_scene.EmbreeScene:
        scene = rtcore_scene.EmbreeScene()
        mesh_construction.TriangleMesh(scene, self.positions[ids].astype(np.float32))
        return scene

    # -- intersection and shading -------------------------------------------------------

    def _intersect(self, local_only: bool, origins, directions):
        """Closest hits: (n,) global triangle (−1 miss), t, u, v."""
        n = len(origins)
        if n == 0:
            empty = np.zeros(0)
            return np.zeros(0, dtype=np.int64), empty, empty, empty
        scene = self._local if local_only else self._all
        if scene is None:
            return np.full(n, -1, dtype=np.int64), np.zeros(n), np.zeros(n), np.zeros(n)
        res = scene.run(
            np.ascontiguousarray(origins, dtype=np.float32),
            np.ascontiguousarray(directions, dtype=np.float32),
            output=1,
        )
        prim = res["primID"].astype(np.int64)
        tri = np.where(prim >= 0, self._local_ids[np.maximum(prim, 0)] if local_only else prim, -1)
        return (
            tri,
            res["tfar"].astype(np.float64),
            res["u"].astype(np.float64),
            res["v"].astype(np.float64),
        )

    def _shading_normal(self, tri, u, v, directions):
        """(n, 3) interpolated unit normal at hits, turned to face against ``directions``."""
        c = self.normals[tri]
        n = (1.0 - u - v)[:, None] * c[:, 0] + u[:, None] * c[:, 1] + v[:, None] * c[:, 2]
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        flip = np.einsum("ij,ij->i", n, directions) > 0.0
        n[flip] = -n[flip]
        return n

    def _face_normal(self, tri, directions):
        """(n, 3) unit face normals of triangles ``tri``, turned to face against ``directions``."""
        c = self.positions[tri]
        f = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
        f /= np.maximum(np.linalg.norm(f, axis=1, keepdims=True), 1e-300)
        flip = np.einsum("ij,ij->i", f, directions) > 0.0
        f[flip] = -f[flip]
        return f

    def _lobe(self, tri, normals, r, directions, lobe):
        """Phong-lobe directions l about r at reflector hits, and which are above the surface.

        ``lobe`` is (N, numpy Generator); a direction below the shading normal's
        plane or the hit triangle's own plane is not above (module docstring).
        """
        exponent, rng = lobe
        lobe_dir = sample_phong(r, exponent, rng.random((len(r), 2)))
        face = self._face_normal(tri, directions)
        above = np.einsum("ij,ij->i", normals, lobe_dir) > 0.0
        return lobe_dir, above & (np.einsum("ij,ij->i", face, lobe_dir) > 0.0)

    def _diffuse_radiance(self, albedo, normals):
        """(n, 3) albedo/π · max(E_sh9(n), 0)."""
        return albedo / np.pi * np.maximum(irradiance_sh9(self.sh9, normals), 0.0)

    def _reflector_terms(self, tri, t, u, v, origins, directions):
        """Point, normal, mirror direction, (n, 3) Fresnel and diffuse term at reflector hits."""
        p = origins + t[:, None] * directions
        n = self._shading_normal(tri, u, v, directions)
        r = directions - 2.0 * np.einsum("ij,ij->i", directions, n)[:, None] * n
        part = self.part[tri]
        fresnel = schlick(self.f0[part], np.einsum("ij,ij->i", r, n)[:, None])
        diffuse = self._diffuse_radiance(self.kd[part], n)
        return p + n * self.ray_offset, n, r, fresnel, diffuse

    def _shade(self, tri, t, u, v, origins, directions, depth, lobe=None):
        """(n, 3) radiance of traced hits (module docstring); ``depth`` traces left.

        ``lobe``: None, reflectors are mirrors; (N, Generator), a reflector hit
        continues along one Phong-lobe sample about its mirror direction.
        """
        out = np.zeros((len(tri), 3))
        miss = tri < 0
        if miss.any():
            out[miss] = sample_latlong(self.environment, directions[miss])
        local = ~miss & (self.part[np.maximum(tri, 0)] < 0)
        if local.any():
            n = self._shading_normal(tri[local], u[local], v[local], directions[local])
            out[local] = self._diffuse_radiance(self.albedo[tri[local]], n)
        refl = ~miss & ~local
        if refl.any():
            o, d = origins[refl], directions[refl]
            p, n, r, fresnel, diffuse = self._reflector_terms(
                tri[refl], t[refl], u[refl], v[refl], o, d
            )
            if lobe is None:
                incident = self.radiance(p, r, depth)
            else:
                lobe_dir, above = self._lobe(tri[refl], n, r, d, lobe)
                incident = np.zeros((len(lobe_dir), 3))
                incident[above] = self.radiance(p[above], lobe_dir[above], depth, lobe)
            out[refl] = (1.0 - fresnel) * diffuse + fresnel * incident
        return out

    def radiance(self, origins, directions, depth: int | None = None, lobe=None):
        """Radiance along rays through the whole scene.

        Parameters
        ----------
        origins, directions
            (n, 3) float, world space; directions need not be unit length.
        depth
            Traces allowed (default :attr:`bounces`); 0 returns black.
        lobe
            None: reflectors met are mirrors; (N, numpy Generator): each continues
            along a Phong-lobe sample of exponent N (module docstring).

        Returns
        -------
        (n, 3) float64
        """
        origins = np.asarray(origins, dtype=np.float64).reshape(-1, 3)
        directions = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        depth = self.bounces if depth is None else depth
        if depth <= 0 or len(origins) == 0:
            return np.zeros((len(origins), 3))
        hit = self._intersect(False, origins, directions)
        return self._shade(*hit, origins, directions, depth - 1, lobe)

    # -- one view -----------------------------------------------------------------------

    def primary_rays(self, camera: OrbitCamera, size: int, samples: int, seed: int = 0):
        """Jittered camera rays.

        Parameters
        ----------
        camera
            Pinhole camera (its ``fov_y``; square images so aspect 1).
        size
            R, pixels per side.
        samples
            Rays per pixel: a jittered √s × √s grid when s is a square, uniform
            jitter otherwise.
        seed
            Seed of the jitter.

        Returns
        -------
        pixels : (R·R·s,) int64
            Pixel index row·R + column of each ray (row 0 at the top).
        origins : (R·R·s, 3) float64
        directions : (R·R·s, 3) float64
            Unit directions.
        """
        rng = np.random.default_rng(seed)
        k = math.isqrt(samples)
        pix = np.repeat(np.arange(size * size), samples)
        if k * k == samples:
            cell = np.tile(np.arange(samples), size * size)
            jitter = np.stack([cell % k, cell // k], axis=1) + rng.random((len(pix), 2))
            jitter /= k
        else:
            jitter = rng.random((len(pix), 2))
        col, row = pix % size + jitter[:, 0], pix // size + jitter[:, 1]
        return (pix, *camera_rays(camera, size, col, row))

    def centre_rays(self, camera: OrbitCamera, size: int):
        """One ray through each pixel centre (column + ½, row + ½), as the playback samples.

        Returns
        -------
        pixels : (R·R,) int64
            row·R + column.
        origins, directions : (R·R, 3) float64
            As :meth:`primary_rays`.
        """
        pix = np.arange(size * size)
        return (pix, *camera_rays(camera, size, pix % size + 0.5, pix // size + 0.5))

    def trace(
        self,
        camera: OrbitCamera,
        size: int = 256,
        samples: int = 4,
        seed: int = 0,
        phong_exponent: float | None = None,
    ):
        """Trace one view into its segmented layers.

        Parameters
        ----------
        camera
            The view.
        size
            R, pixels per side.
        samples
            Rays per pixel (≥ 1).
        seed
            Seed of the pixel jitter (and, with ``phong_exponent``, of the lobe draws).
        phong_exponent
            N of a glossy reflector: each reflector sample draws one direction of
            the Phong lobe about r (module docstring); None or 0: mirrors.

        Returns
        -------
        TracedView
        """
        if size < 1 or samples < 1:
            raise ValueError(f"size {size} and samples {samples} must be at least 1")
        exponent = float(phong_exponent or 0.0)
        if not (math.isfinite(exponent) and exponent >= 0.0):
            raise ValueError(f"phong exponent {exponent:g}: expected N > 0, or 0 for a mirror")
        lobe = (exponent, np.random.default_rng([seed, LOBE_STREAM])) if exponent else None
        start = time.perf_counter()
        pix, origins, dirs = self.primary_rays(camera, size, samples, seed)
        tri, t, u, v = self._intersect(False, origins, dirs)
        part = np.where(tri >= 0, self.part[np.maximum(tri, 0)], -1)
        refl = part >= 0
        radiance = np.zeros((len(pix), 3))
        back = ~refl
        radiance[back] = self._shade(
            tri[back], t[back], u[back], v[back], origins[back], dirs[back], 0
        )

        # reflector samples: Figure 4's layers
        ri = np.flatnonzero(refl)
        p, nrm, r, fresnel, diffuse = self._reflector_terms(
            tri[ri], t[ri], u[ri], v[ri], origins[ri], dirs[ri]
        )
        if lobe is None:
            lobe_dir, above = r, np.ones(len(ri), dtype=bool)
        else:  # one lobe direction per sample; those below the surface carry nothing
            lobe_dir, above = self._lobe(tri[ri], nrm, r, dirs[ri], lobe)
        go = np.flatnonzero(above)
        hit2 = self._intersect(False, p[go], lobe_dir[go])
        incident = np.zeros((len(ri), 3))
        incident[go] = self._shade(*hit2, p[go], lobe_dir[go], self.bounces - 1, lobe)
        is_local = np.zeros(len(ri), dtype=bool)
        is_local[go] = (hit2[0] >= 0) & (self.part[np.maximum(hit2[0], 0)] >= 0)
        distant = incident.copy()
        if is_local.any():
            li = np.flatnonzero(is_local)
            hit3 = self._intersect(True, p[li], lobe_dir[li])
            distant[li] = self._shade(*hit3, p[li], lobe_dir[li], 0)
        radiance[ri] = (1.0 - fresnel) * diffuse + fresnel * incident

        n_parts, npix = len(self.part_names), size * size
        bins = part[ri] * npix + pix[ri]

        def acc(weights):
            w = np.asarray(weights, dtype=np.float64)
            cols = w.reshape(len(ri), w.shape[1] if w.ndim == 2 else 1)  # no pixel: none
            sums = [
                np.bincount(bins, cols[:, c], minlength=n_parts * npix)
                for c in range(cols.shape[1])
            ]
            out = np.stack(sums, axis=-1).reshape(n_parts, size, size, -1)
            return out if w.ndim == 2 else out[..., 0]

        count = acc(np.ones(len(ri)))
        local_count = acc(is_local.astype(np.float64))
        safe = np.maximum(count, 1.0)
        local_safe = np.maximum(local_count, 1.0)[..., None]

        def image(values):
            return (
                np.stack(
                    [np.bincount(pix, values[:, c], minlength=npix) for c in range(3)], axis=-1
                ).reshape(size, size, 3)
                / samples
            )

        return TracedView(
            camera=camera,
            size=size,
            samples=samples,
            part_names=list(self.part_names),
            composite=image(radiance).astype(np.float32),
            background=image(np.where(refl[:, None], 0.0, radiance)).astype(np.float32),
            coverage=(count / samples).astype(np.float32),
            diffuse=(acc(diffuse) / safe[..., None]).astype(np.float32),
            fresnel=(acc(fresnel.mean(axis=1)) / safe).astype(np.float32),
            distant=(acc(distant) / safe[..., None]).astype(np.float32),
            local_rgb=(acc(incident * is_local[:, None]) / local_safe).astype(np.float32),
            local_alpha=(local_count / safe).astype(np.float32),
            seconds=time.perf_counter() - start,
            ray_pixel=pix[ri],
            ray_part=part[ri],
            ray_point=p.astype(np.float32),
            ray_normal=nrm.astype(np.float32),
            ray_direction=r.astype(np.float32),
            phong_exponent=exponent,
        )


def trace_view(
    scene: Scene,
    camera: OrbitCamera,
    size: int = 256,
    samples: int = 4,
    seed: int = 0,
    bounces: int = TRACE_BOUNCES,
    phong_exponent: float | None = None,
) -> TracedView:
    """One view's segmented layers (builds a :class:`SceneTracer`; reuse one for many views)."""
    return SceneTracer(scene, bounces).trace(camera, size, samples, seed, phong_exponent)
