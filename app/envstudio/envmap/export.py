"""``envstudio envmap``: an environment converted on the GPU to any representation, as EXR."""

from __future__ import annotations

import os
from pathlib import Path

import moderngl

from envstudio.envmap import conversions
from envstudio.gpu.programs import ProgramLibrary

REPRESENTATIONS = ("latlong", "cube", "paraboloid", "spheremap")


def export_environment(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    latlong: moderngl.Texture,
    representation: str,
    size: int,
    border: int,
    path: str | os.PathLike,
) -> Path:
    """Convert a lat-long texture through the cube map into ``representation`` and save it.

    Parameters
    ----------
    latlong
        Source lat-long texture (conversions.upload_latlong).
    representation
        One of :data:`REPRESENTATIONS`.
    size
        Cube face edge; for the others the output size (lat-long: height, 2·size wide;
        paraboloid: face edge; sphere map: edge).
    border
        Dual-paraboloid border in texels.
    path
        Output ``.exr``.
    """
    cube = conversions.latlong_to_cube(ctx, programs, latlong, size)
    try:
        if representation == "cube":
            return conversions.save_cube_exr(path, cube)
        make, save = {
            "latlong": (
                lambda: conversions.cube_to_latlong(ctx, programs, cube, size),
                conversions.save_latlong_exr,
            ),
            "paraboloid": (
                lambda: conversions.cube_to_paraboloid(ctx, programs, cube, size, border),
                conversions.save_paraboloid_exr,
            ),
            "spheremap": (
                lambda: conversions.cube_to_spheremap(ctx, programs, cube, size),
                conversions.save_spheremap_exr,
            ),
        }[representation]
        tex = make()
        try:
            return save(path, tex)
        finally:
            tex.release()
    finally:
        cube.release()
