"""Our scenes rebuilt in Mitsuba 3, the independent renderer the reference is checked against.

Mitsuba runs in its ``scalar_rgb`` variant: plain C++ on the CPU with RGB
radiance as ours, nothing compiled or fetched at run time. (``llvm_ad_rgb``
needs a system libLLVM that Dr.Jit 1.5 can drive: Debian 12's LLVM 15 aborts
on its kernels, "Cannot select ... fminimum", and LLVM 14 is refused.)
Everything is built from our own scene graph
(:class:`envstudio.scene.graph.Scene`) so both renderers see the same input.

Conventions, derived here and proven in tests/test_mitsuba_gl.py:

Environment
    Mitsuba's ``envmap`` (src/emitters/envmap.cpp) looks a world direction d
    up at ``uv = (atan2(x', -z') / 2π, acos(y') / π)`` of d' = to_world⁻¹ d.
    Ours (core/latlong.py) is ``u = 0.5 + atan2(x, -z) / 2π``, ``v = acos(y) / π``.
    With ``to_world`` the rotation by 180° about +Y, diag(−1, 1, −1), d' =
    (−x, y, −z) and atan2(−x, z) = atan2(x, −z) ± π, so Mitsuba's u is
    atan2(x, −z) / 2π ± ½ ≡ our u (mod 1, the map is periodic) and its v,
    acos(y) / π, is ours: :data:`ENVIRONMENT_TO_WORLD`.
Texel grid
    Mitsuba interpolates bilinearly between samples at u = (j + ½) / W′
    (a periodic extra column) and v = i / (H′ − 1): its first and last rows
    lie on the poles. Ours is constant over each texel of an (H, W) map.
    :func:`environment_bitmap` resamples ours onto Mitsuba's grid at
    :data:`UPSAMPLE` samples per texel (W′ = kW, H′ = kH + 1): every sample
    takes the value of the texel it falls in, a sample on a row boundary the
    mean of the two rows. Mitsuba then returns our texel exactly except within
    one sample step of a row edge and half a step of a column edge, where the
    linear blend has the same integral as the step it replaces.
Camera
    Mitsuba's ``perspective`` sensor with ``to_world = look_at(eye, target,
    +Y)``, ``fov_axis = "y"`` and our ``fov_y`` shoots, through the centre of
    pixel (row, column) (row 0 at the top), the ray that our view and
    projection matrices (core/transforms.py) unproject at that pixel.
Reflectors
    Each reflector node becomes a Mitsuba mesh in world space (model matrix
    applied to positions, its inverse transpose to the vertex normals) with
    the same interpolated shading normals. Its BSDF is one-sided, as
    Mitsuba's are by default: a shading normal turned from the viewer
    reflects nothing, as in ours (reference/accumulate.glsl). Ours also
    shades the back of a face met by a traced ray, which Mitsuba's leaves
    black; on the closed meshes compared here no ray from outside meets one.

The integrator is ``path`` with ``hide_emitters``: the environment seen
directly is black and has alpha 0, so an RGBA film's rgb / alpha is the mean
over the part of a pixel that the reflector covers.
"""

from __future__ import annotations

from dataclasses import dataclass

import drjit as dr
import mitsuba as mi
import numpy as np
import numpy.typing as npt

from envstudio.scene.camera import OrbitCamera
from envstudio.scene.graph import Scene

VARIANT = "scalar_rgb"
mi.set_variant(VARIANT)

#: Mitsuba samples per texel along each axis of our lat-long map.
UPSAMPLE = 4
#: Emitter-to-world transform that makes Mitsuba's envmap read our lat-long convention.
ENVIRONMENT_TO_WORLD = mi.ScalarTransform4f(np.diag([-1.0, 1.0, -1.0, 1.0]).tolist())


def environment_bitmap(radiance: npt.ArrayLike, upsample: int | None = None) -> npt.NDArray:
    """Our piecewise-constant lat-long map on Mitsuba's bilinear sample grid.

    Parameters
    ----------
    radiance
        (h, w, 3) linear RGB, our convention (row 0 at +Y, texel centres at
        ((j + ½) / w, (i + ½) / h)).
    upsample
        Samples per texel along each axis, k (default :data:`UPSAMPLE`).

    Returns
    -------
    (k h + 1, k w, 3) float32
        Sample (i, j) at Mitsuba's (u, v) = ((j + ½) / (k w), i / (k h)):
        the texel it lies in, or the mean of the two texels whose shared
        row boundary it lies on (rows 0 and k h are the poles).
    """
    upsample = UPSAMPLE if upsample is None else int(upsample)
    img = np.asarray(radiance, dtype=np.float32)
    h, w = img.shape[:2]
    rows = np.arange(upsample * h + 1)
    above = np.clip((rows - 1) // upsample, 0, h - 1)
    below = np.clip(rows // upsample, 0, h - 1)
    cols = np.arange(upsample * w) // upsample
    return 0.5 * (img[above][:, cols] + img[below][:, cols])


def environment_emitter(radiance: npt.ArrayLike, upsample: int | None = None) -> dict:
    """Mitsuba ``envmap`` plugin dictionary of our lat-long map (see the module notes)."""
    bitmap = mi.Bitmap(np.ascontiguousarray(environment_bitmap(radiance, upsample)))
    return {"type": "envmap", "bitmap": bitmap, "to_world": ENVIRONMENT_TO_WORLD}


def sensor(camera: OrbitCamera, size: tuple[int, int], spp: int = 64) -> dict:
    """Mitsuba ``perspective`` sensor of ``camera`` with a box-filtered RGBA film.

    Parameters
    ----------
    camera
        Our orbit camera (eye, target, +Y up, vertical field of view).
    size
        (width, height) in pixels.
    spp
        Default samples per pixel (``mi.render`` takes its own).
    """
    w, h = size
    return {
        "type": "perspective",
        "fov": float(camera.fov_y),
        "fov_axis": "y",
        "near_clip": float(camera.near),
        "far_clip": float(camera.far),
        "to_world": mi.ScalarTransform4f().look_at(
            origin=[float(c) for c in camera.position],
            target=[float(c) for c in camera.target],
            up=[0.0, 1.0, 0.0],
        ),
        "film": {
            "type": "hdrfilm",
            "width": int(w),
            "height": int(h),
            "pixel_format": "rgba",
            "component_format": "float32",
            # samples uniform over the pixel only: the box of our footprint, no wider
            "sample_border": False,
            "rfilter": {"type": "box"},
        },
        "sampler": {"type": "independent", "sample_count": int(spp)},
    }


def diffuse_bsdf(kd: float) -> dict:
    """Lambertian reflectance ``kd`` (ours: ``model=phong``, ``kd``, ``fresnel=0``)."""
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": [float(kd)] * 3}}


def ggx_bsdf(alpha: float) -> dict:
    """GGX conductor with F = 1 (ours: ``model=microfacet``, ``kd=0``, ``fresnel=1``).

    Mitsuba's Smith term is the separable G1(wi) G1(wo); ours is the
    height-correlated one. They agree away from grazing (tests/test_mitsuba_gl.py).
    """
    return {
        "type": "roughconductor",
        "material": "none",
        "distribution": "ggx",
        "alpha": float(alpha),
    }


def schlick_ggx_bsdf(alpha: float, f0: tuple[float, float, float]) -> dict:
    """GGX with Schlick's F(v·h) of ``f0`` per RGB channel (ours: ``model=microfacet``,
    ``kd=0``, ``fresnel=f0``): Mitsuba's ``principled`` with ``metallic = 1``,
    ``base_color = f0`` and ``roughness = √alpha`` (its alpha is roughness²).

    The convention, checked against Mitsuba 3.9.1's own ``eval``: with metallic 1 the
    principled BSDF is its metal lobe alone, GGX D with the separable Smith G1(wi) G1(wo)
    of ``roughconductor`` times ``calc_schlick(base_color, wi·h)`` = base_color + (1 −
    base_color)(1 − wi·h)^5, the same Schlick as ours (shaders/common/fresnel.glsl);
    principled and roughconductor × Schlick agree to 4e-7 relative at random directions.
    Mitsuba's ``roughconductor`` with a ``specular_reflectance`` tint is not this: its F is
    the tint times a conductor's exact Fresnel (F = tint for ``material="none"``), constant
    in angle, where Schlick rises to 1 at grazing.
    """
    return {
        "type": "principled",
        "base_color": {"type": "rgb", "value": [float(c) for c in f0]},
        "metallic": 1.0,
        "roughness": float(np.sqrt(alpha)),
    }


def reflector_meshes(scene: Scene, bsdf: dict) -> dict[str, mi.Mesh]:
    """World-space Mitsuba meshes of the scene's reflectors, all with ``bsdf``.

    Raises
    ------
    ValueError
        The scene has local objects: ours shade them by SH irradiance, which
        no Mitsuba material reproduces.
    """
    if scene.local_objects():
        raise ValueError(f"{scene.name}: local objects have no Mitsuba counterpart")
    meshes = {}
    for index, node in enumerate(scene.reflectors()):
        model = node.transform.matrix().astype(np.float64)
        positions = node.mesh.positions @ model[:3, :3].T + model[:3, 3]
        normals = node.mesh.normals @ np.linalg.inv(model[:3, :3]).T
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
        props = mi.Properties()
        props["bsdf"] = mi.load_dict(bsdf)
        mesh = mi.Mesh(
            node.name, len(positions), node.mesh.triangle_count, props, has_vertex_normals=True
        )
        params = mi.traverse(mesh)
        params["vertex_positions"] = np.ascontiguousarray(positions, np.float32).ravel()
        params["vertex_normals"] = np.ascontiguousarray(normals, np.float32).ravel()
        params["faces"] = np.ascontiguousarray(node.mesh.indices, np.uint32).ravel()
        params.update()
        meshes[f"reflector{index}"] = mesh
    return meshes


def load_scene(scene: Scene, size: tuple[int, int], bsdf: dict, max_depth: int) -> mi.Scene:
    """The Mitsuba scene of ``scene``: camera, reflectors with ``bsdf``, environment.

    Parameters
    ----------
    scene
        Our scene (reflectors only).
    size
        (width, height) of the film.
    bsdf
        Mitsuba BSDF dictionary (:func:`diffuse_bsdf`, :func:`ggx_bsdf`).
    max_depth
        Mitsuba's longest path in segments: 2 is direct lighting (the first
        hit sees the environment or nothing), each more allows one more
        bounce off a reflector.
    """
    return mi.load_dict(
        {
            "type": "scene",
            "integrator": {
                "type": "path",
                "max_depth": int(max_depth),
                # no Russian roulette: every path runs to max_depth
                "rr_depth": 1000,
                "hide_emitters": True,
            },
            "sensor": sensor(scene.camera, size),
            "environment": environment_emitter(scene.environment.radiance),
            **reflector_meshes(scene, bsdf),
        }
    )


@dataclass
class Estimate:
    """A Mitsuba image with its per-pixel standard error.

    Attributes
    ----------
    mean : (h, w, 3) float64
        Radiance, row 0 at the top (0 where nothing was hit).
    standard_error : (h, w, 3) float64
        Standard error of ``mean``.
    coverage : (h, w) float64
        Fraction of the estimate's samples that hit a reflector.
    samples : int
        Samples per pixel.
    """

    mean: npt.NDArray[np.float64]
    standard_error: npt.NDArray[np.float64]
    coverage: npt.NDArray[np.float64]
    samples: int


def render_footprint(scene: mi.Scene, spp: int, batches: int, seed: int = 0) -> Estimate:
    """Box-filtered pixels, each the mean over the part of its footprint on a reflector.

    ``batches`` independent ``mi.render`` calls of ``spp`` samples (seeds
    ``seed``, ``seed + 1``, ...). The RGBA film's rgb is the sum over the
    pixel's samples of the radiance of those that hit (the environment is
    hidden) over the sample count, its alpha the fraction that hit: the ratio
    of their sums over the batches is the covered part's mean (our
    ``pixel_filter=true``), its standard error that of a ratio estimator
    from the spread of the batches.
    """
    rgb, alpha = [], []
    for batch in range(batches):
        image = np.array(mi.render(scene, spp=spp, seed=seed + batch), dtype=np.float64)
        rgb.append(image[..., :3])
        alpha.append(image[..., 3:])
    rgb, alpha = np.array(rgb), np.array(alpha)
    a = alpha.mean(0)
    safe = np.where(a > 0, a, 1.0)
    mean = np.where(a > 0, rgb.mean(0) / safe, 0.0)
    residual = rgb - mean * alpha
    error = np.sqrt(np.sum(residual**2, 0) / (batches * (batches - 1))) / safe
    return Estimate(mean, np.where(a > 0, error, 0.0), a[..., 0], spp * batches)


def centre_rays(scene: mi.Scene) -> tuple[list[list[mi.Ray3f]], npt.NDArray[np.float64]]:
    """Camera rays through the pixel centres and the shading normal's n·v where they hit.

    Returns
    -------
    rays : list of rows of mi.Ray3f
        Row 0 at the top.
    n_dot_v : (h, w) float64
        Interpolated (shading) normal · direction to the eye at the hit; NaN
        where the ray misses every reflector.
    """
    camera = scene.sensors()[0]
    w, h = camera.film().size()
    rays, n_dot_v = [], np.full((h, w), np.nan)
    for row in range(h):
        rays.append([])
        for col in range(w):
            position = mi.Point2f((col + 0.5) / w, (row + 0.5) / h)
            ray, _ = camera.sample_ray(0.0, 0.5, position, mi.Point2f(0.5))
            rays[-1].append(ray)
            hit = scene.ray_intersect(ray)
            if hit.is_valid():
                n_dot_v[row, col] = -float(dr.dot(hit.sh_frame.n, ray.d))
    return rays, n_dot_v


def render_centres(
    scene: mi.Scene, spp: int, mask: npt.ArrayLike | None = None, seed: int = 0
) -> Estimate:
    """Every pixel's centre ray only (our ``pixel_filter=false``), ``spp`` paths each.

    Parameters
    ----------
    scene
        From :func:`load_scene`.
    spp
        Paths per pixel.
    mask
        (h, w) bool: the pixels to render (default: those whose centre ray
        hits a reflector); the others are 0.
    seed
        Seed of the independent sampler.

    Returns
    -------
    Estimate
        The sample mean and its standard error from the paths' own spread.
    """
    rays, n_dot_v = centre_rays(scene)
    mask = np.isfinite(n_dot_v) if mask is None else np.asarray(mask, bool)
    integrator = scene.integrator()
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(seed)
    h, w = n_dot_v.shape
    total, squares = np.zeros((h, w, 3)), np.zeros((h, w, 3))
    for row, col in zip(*np.nonzero(mask), strict=True):
        ray = rays[row][col]
        values = np.empty((spp, 3))
        for i in range(spp):
            values[i] = integrator.sample(scene, sampler, ray)[0]
        total[row, col] = values.sum(0)
        squares[row, col] = np.sum(values**2, 0)
    mean = total / spp
    variance = np.maximum(squares / spp - mean**2, 0.0) * spp / (spp - 1)
    return Estimate(mean, np.sqrt(variance / spp), mask.astype(np.float64), spp)


def emitter_radiance(emitter: mi.Emitter, directions: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(n, 3) radiance an environment ``emitter`` sends from the world ``directions`` (n, 3).

    ``emitter.eval`` of an interaction whose ``wi`` points back along the
    direction, as Mitsuba evaluates an escaped ray.
    """
    out = []
    for d in np.asarray(directions, dtype=np.float64):
        interaction = mi.SurfaceInteraction3f()
        interaction.wi = mi.Vector3f(*(-d))
        out.append(np.array(emitter.eval(interaction), dtype=np.float64))
    return np.array(out).reshape(-1, 3)
