"""Mip chains of cube maps: the hardware box filter and a cross-face filter.

Seed 000 (section 4.2) builds the glossy prefilter with the hardware's automatic
mip-map generation, a 2 × 2 box filter inside each face. Section 6 (Figure 4)
names its drawback: every face is filtered alone, so at a high level the six faces
hold six unrelated averages and their borders show when the LOD bias b is large.
:func:`build_cross_face_mipmaps` rebuilds levels 1 … with
shaders/envmap/cross_face_mip.glsl, a tent filter whose footprint continues across
face edges; :func:`edge_jumps` measures what is left of the seam.

Both need textures with storage for every level: :func:`mipmapped_cube` makes one.
Compute shaders need OpenGL 4.3. :func:`write_cube_level` fills any level from the CPU
(a prefiltered chain's levels, one lobe each), which moderngl's ``TextureCube.write``
cannot (level 0 only).
"""

from __future__ import annotations

import ctypes

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core import cubemap
from envstudio.gpu.programs import ProgramLibrary
from envstudio.gpu.uniforms import set_uniform

__all__ = ["build_cross_face_mipmaps", "edge_jumps", "mipmapped_cube", "write_cube_level"]

_PROGRAM = "envmap/cross_face_mip.glsl"
_GL_TEXTURE_CUBE_MAP_POSITIVE_X = 0x8515
_GL_RGB = 0x1907
_GL_FLOAT = 0x1406
_GL_UNPACK_ALIGNMENT = 0x0CF5
#: glTexSubImage2D(target, level, x, y, width, height, format, type, pixels)
_TEX_SUB_IMAGE_2D = ctypes.CFUNCTYPE(
    None,
    *(ctypes.c_uint, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int),
    ctypes.c_uint,
    ctypes.c_uint,
    ctypes.c_void_p,
)
_PIXEL_STORE_I = ctypes.CFUNCTYPE(None, ctypes.c_uint, ctypes.c_int)


def mipmapped_cube(ctx: moderngl.Context, size: int) -> moderngl.TextureCube:
    """An RGBA32F cube map of ``size`` with storage for its full mip chain.

    Parameters
    ----------
    ctx
        The context that owns it.
    size
        Face edge n of level 0 in texels.

    Returns
    -------
    moderngl.TextureCube
        Zero-filled, trilinear filtering (``LINEAR_MIPMAP_LINEAR``). The caller releases it.
    """
    cube = ctx.texture_cube((size, size), 4, dtype="f4")
    cube.build_mipmaps()  # allocates levels 1 … log2(n); their content is overwritten later
    cube.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
    return cube


def write_cube_level(cube: moderngl.TextureCube, level: int, faces: npt.ArrayLike) -> None:
    """Write the six faces of one mip level of ``cube`` (with storage for it) from the CPU.

    moderngl's ``TextureCube.write`` reaches level 0 only, so this calls
    ``glTexSubImage2D`` (OpenGL 1.1) itself, through the loader moderngl loads every GL
    function from (``ctx.mglo._context``, as ui/imgui_renderer.py's state query). The cube
    is left bound to texture unit 0.

    Parameters
    ----------
    cube
        Cube map with storage for ``level`` (:func:`mipmapped_cube`).
    level
        Mip level k; its faces are m = n >> k texels wide.
    faces
        (6, m, m, 3) float linear radiance, core.cubemap layout (OpenGL face order, rows ↔ t).
    """
    data = np.ascontiguousarray(faces, dtype=np.float32)
    m = max(1, cube.size[0] >> level)
    if data.shape != (6, m, m, 3):
        raise ValueError(
            f"level {level} of a {cube.size[0]}² cube takes (6, {m}, {m}, 3), got {data.shape}"
        )
    loader = cube.ctx.mglo._context
    sub_image = _TEX_SUB_IMAGE_2D(loader.load_opengl_function("glTexSubImage2D"))
    pixel_store = _PIXEL_STORE_I(loader.load_opengl_function("glPixelStorei"))
    cube.use(location=0)
    pixel_store(_GL_UNPACK_ALIGNMENT, 1)
    for face in range(6):
        sub_image(
            _GL_TEXTURE_CUBE_MAP_POSITIVE_X + face,
            level,
            0,
            0,
            m,
            m,
            _GL_RGB,
            _GL_FLOAT,
            data[face].ctypes.data,
        )


def build_cross_face_mipmaps(
    ctx: moderngl.Context, programs: ProgramLibrary, cube: moderngl.TextureCube
) -> None:
    """Rebuild levels 1 … log2(n) of ``cube`` from its level 0 with the cross-face filter.

    Parameters
    ----------
    ctx, programs
        Context (OpenGL 4.3 or later) and its program library.
    cube
        RGBA32F cube map with mip storage (:func:`mipmapped_cube`); level 0 is read,
        every other level is overwritten. Seamless cube sampling must be on (moderngl
        turns it on for every context).
    """
    program = programs.compute(_PROGRAM)
    sampler = ctx.sampler(
        filter=(moderngl.LINEAR_MIPMAP_NEAREST, moderngl.LINEAR), texture=cube
    )  # exactly level k − 1, bilinear (and seamless) inside it
    try:
        sampler.use(0)
        set_uniform(program, "u_source", 0)
        size = cube.size[0]
        level = 1
        while size >> level >= 1:
            m = size >> level
            cube.bind_to_image(0, read=False, write=True, level=level)
            set_uniform(program, "u_level", level)
            set_uniform(program, "u_size", m)
            groups = (m + 7) // 8
            program.run(groups, groups, 6)
            ctx.memory_barrier(
                moderngl.TEXTURE_FETCH_BARRIER_BIT | moderngl.SHADER_IMAGE_ACCESS_BARRIER_BIT
            )
            level += 1
    finally:
        sampler.clear(0)
        sampler.release()


def edge_jumps(faces: npt.ArrayLike) -> tuple[dict[tuple[int, int], float], float]:
    """Mean step between neighbouring texels across each of the 12 face edges and inside faces.

    Every boundary texel of every face is paired with the texel on the other side of
    its edge (found by the direction half a texel beyond the face, on the extended face
    plane); inside a face, every texel with its right and upper neighbour. A step is
    the mean over channels of |a − b|.

    Parameters
    ----------
    faces
        (6, m, m, c) float, one mip level in core.cubemap layout (m ≥ 2).

    Returns
    -------
    across
        {(f, g): mean step} for the 12 edges, keyed by the two faces (f < g).
    inside
        Mean step between neighbours inside the faces.
    """
    faces = np.asarray(faces, dtype=np.float64)
    if faces.ndim != 4 or faces.shape[0] != 6 or faces.shape[1] != faces.shape[2]:
        raise ValueError(f"cube faces must have shape (6, m, m, c), got {faces.shape}")
    m = faces.shape[1]
    if m < 2:
        raise ValueError("edge jumps need faces of at least 2 x 2 texels")
    centres = (np.arange(m) + 0.5) / m
    steps: dict[tuple[int, int], list[npt.NDArray[np.float64]]] = {}
    for face in range(6):
        for beyond in (-0.5 / m, 1.0 + 0.5 / m):
            for uv in (
                np.stack([np.full(m, beyond), centres], -1),
                np.stack([centres, np.full(m, beyond)], -1),
            ):
                inner = np.clip((uv * m).astype(np.int64), 0, m - 1)
                other, other_uv = cubemap.direction_to_uv(cubemap.uv_to_direction(face, uv))
                outer = np.clip((other_uv * m).astype(np.int64), 0, m - 1)
                a = faces[face, inner[:, 1], inner[:, 0]]
                b = faces[other, outer[:, 1], outer[:, 0]]
                key = (min(face, int(other[0])), max(face, int(other[0])))
                steps.setdefault(key, []).append(np.abs(a - b).mean(axis=-1))
    across = {key: float(np.concatenate(v).mean()) for key, v in sorted(steps.items())}
    inside = np.concatenate(
        [
            np.abs(np.diff(faces, axis=1)).mean(axis=-1).ravel(),
            np.abs(np.diff(faces, axis=2)).mean(axis=-1).ravel(),
        ]
    )
    return across, float(inside.mean())
