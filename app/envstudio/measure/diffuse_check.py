"""Each method's own diffuse term against brute-force irradiance on a sphere.

Every method that declares seed 000 eq. 8's ``kd`` and ``fresnel`` renders a
unit sphere twice, with k_d = 1 and k_d = 0 (f_λ = 0, so F = (1 − n·v)⁵ is
Schlick's at normal incidence 0). The difference is its diffuse part,
(1 − F) · E(n)/π by its own means (SH, Miller's map, Lambertian radiance maps);
it is held against the same product with E(n) summed over every texel of the
environment (prefilter.brute_force.irradiance, exact texel solid angles), over the
pixels whose n·v exceeds :data:`CORE_COSINE` (where 1 − F > 0.83 and the pixel
footprint stays small). Errors are relative, in luminance, per pixel.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.core.env_sampling import luminance
from envstudio.engine.session import RenderSession
from envstudio.prefilter.brute_force import downsample_latlong, irradiance
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import uv_sphere

__all__ = ["CORE_COSINE", "DiffuseError", "diffuse_errors", "sphere_pixels", "sphere_scene"]

#: Pixels with n·v above this are measured.
CORE_COSINE = 0.3
#: Rows of the environment the brute-force irradiance sums (box-filtered, power-preserving).
BRUTE_FORCE_HEIGHT = 256


@dataclass(frozen=True)
class DiffuseError:
    """One method's diffuse part against brute force.

    Attributes
    ----------
    method : str
    settings : str
        The parameter assignments it ran with ("" for its defaults).
    mean, maximum, bias : float
        Mean and largest relative error and the mean signed relative error (luminance).
    pixels : int
        Pixels measured.
    """

    method: str
    settings: str
    mean: float
    maximum: float
    bias: float
    pixels: int


def sphere_scene(environment: Environment) -> Scene:
    """A unit sphere (96 rings) at the origin seen from 3 units along +z, fov 45°."""
    camera = OrbitCamera(azimuth=0.0, elevation=0.0, distance=3.0, fov_y=45.0)
    return Scene(environment, [Node("sphere", uv_sphere(1.0, 96, 192))], camera, "sphere")


def sphere_pixels(
    camera: OrbitCamera, size: tuple[int, int]
) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Hit mask, normal and direction to the eye of the unit sphere per pixel centre.

    Parameters
    ----------
    camera
        The camera.
    size
        (width, height) in pixels.

    Returns
    -------
    hit : (h, w) bool
    normal, view : (h, w, 3) float64
        Unit normal at the hit and unit direction toward the eye (row 0 at the top).
    """
    w, h = size
    clip_to_world = np.linalg.inv(
        camera.projection_matrix(w / h).astype(np.float64) @ camera.view_matrix().astype(np.float64)
    )
    x = (np.arange(w) + 0.5) / w * 2 - 1
    y = 1 - (np.arange(h) + 0.5) / h * 2
    X, Y = np.meshgrid(x, y)
    ones = np.ones_like(X)
    near = np.stack([X, Y, -ones, ones], -1) @ clip_to_world.T
    far = np.stack([X, Y, ones, ones], -1) @ clip_to_world.T
    origin = near[..., :3] / near[..., 3:]
    direction = far[..., :3] / far[..., 3:] - origin
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    b = np.sum(origin * direction, -1)
    disc = b * b - (np.sum(origin * origin, -1) - 1.0)
    hit = disc > 0
    t = -b - np.sqrt(np.where(hit, disc, 0.0))
    return hit, origin + t[..., None] * direction, -direction


def diffuse_errors(
    environment: Environment,
    runs: Sequence[tuple[str, Sequence[str]]],
    size: tuple[int, int] = (64, 64),
    cube_size: int = 128,
    ctx=None,
) -> list[DiffuseError]:
    """The diffuse part of each run against brute-force irradiance (module docstring).

    Parameters
    ----------
    environment
        The lighting.
    runs
        (method name, ``name=value`` assignments) pairs.
    size
        Image (width, height).
    cube_size
        Face edge of the scene's cube map.
    ctx
        A moderngl context to render in, else the session makes one.

    Returns
    -------
    list of DiffuseError
        One per run, in order.
    """
    session = RenderSession(sphere_scene(environment), ctx=ctx, cube_size=cube_size)
    try:
        hit, normal, view = sphere_pixels(session.camera, size)
        cosine = np.sum(normal * view, -1)
        core = hit & (cosine > CORE_COSINE)
        radiance = environment.radiance
        if radiance.shape[0] > BRUTE_FORCE_HEIGHT:
            radiance = downsample_latlong(radiance, BRUTE_FORCE_HEIGHT)
        weight = 1.0 - (1.0 - cosine[core]) ** 5
        expected = luminance(weight[:, None] * irradiance(radiance, normal[core]) / np.pi)
        session.renderer.display["background"] = False
        results = []
        for name, assignments in runs:
            method = session.method(name)
            session.apply(method, [*assignments, "fresnel=0"])
            parts = []
            for kd in (1.0, 0.0):
                method.values["kd"] = kd
                session.render_offscreen(method, size)
                parts.append(session.read_hdr())
            got = luminance((parts[0] - parts[1])[core])
            relative = got / expected - 1.0
            results.append(
                DiffuseError(
                    name,
                    " ".join(assignments),
                    float(np.mean(np.abs(relative))),
                    float(np.max(np.abs(relative))),
                    float(np.mean(relative)),
                    int(core.sum()),
                )
            )
        return results
    finally:
        session.release()
