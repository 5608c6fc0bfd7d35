"""Environment maps on the GPU: upload, conversion between parameterizations, readback, EXR.

Representations (conventions of core.latlong, core.cubemap, core.paraboloid and
core.spheremap, after DESIGN.md "Conventions"):

- lat-long: ``moderngl.Texture`` of (w, h) = (2h, h); texture (s, t) = (u, v),
  ``REPEAT`` in s, clamped in t, linear filtering;
- cube: ``moderngl.TextureCube`` RGBA32F in OpenGL face order with its full mip
  chain and trilinear filtering, sampled seamlessly across faces (moderngl
  enables ``GL_TEXTURE_CUBE_MAP_SEAMLESS``);
- dual paraboloid: ``moderngl.TextureArray`` of (n, n, 2), RGBA32F, layer 0 the
  front face (z ≥ 0) and layer 1 the back, clamped, linear filtering;
- sphere map: ``moderngl.Texture`` of (n, n), RGBA32F, clamped, linear filtering.

Render targets are RGBA32F: half floats overflow at 65504, which the sun of an
HDR environment exceeds, and RGB32F is not a format GL must render to.

Every conversion runs shaders/envmap/resample.glsl, one fragment per target
texel, sampling the source bilinearly at mip level 0: exactly what
core.resample computes on the CPU. moderngl cannot attach a cube face (or one
layer of an array) to a framebuffer, so cube faces and paraboloid layers are
rendered one at a time into a scratch 2D target and copied into place through a
pixel buffer, without leaving the GPU.

Row order: GL stores row 0 at t = 0 and reads it back first, and the arrays of
core use the same order, so nothing is flipped between them; for a lat-long map
t = v, so row 0 is +Y both in the texture and in the image file. Only the EXR
writers of the dual paraboloid and sphere map flip rows, so that those pictures
are stored upright (+Y at the top).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core import cubemap, paraboloid, spheremap
from envstudio.core.resample import latlong_supersampling
from envstudio.errors import InputFileError
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.gpu.programs import ProgramLibrary
from envstudio.io.images import write_image

__all__ = [
    "cube_to_latlong",
    "cube_to_paraboloid",
    "cube_to_spheremap",
    "latlong_to_cube",
    "paraboloid_to_cube",
    "read_cube",
    "read_texture",
    "save_cube_exr",
    "save_latlong_exr",
    "save_paraboloid_exr",
    "save_spheremap_exr",
    "spheremap_to_cube",
    "upload_latlong",
]

# Representation codes of shaders/envmap/resample.glsl (its ENVMAP_* defines).
_LATLONG, _CUBE, _PARABOLOID, _SPHEREMAP = 0, 1, 2, 3
_RESAMPLE = "envmap/resample.glsl"
_DTYPES = {"f1": np.uint8, "f2": np.float16, "f4": np.float32}


def upload_latlong(ctx: moderngl.Context, image: npt.ArrayLike) -> moderngl.Texture:
    """Upload a lat-long environment as an RGB32F texture.

    Parameters
    ----------
    ctx
        The context that will own the texture.
    image
        (h, w, 3) float, linear radiance, row 0 = +Y (as io.images.read_environment returns).

    Returns
    -------
    moderngl.Texture
        (w, h) RGB32F, uploaded row 0 first so that (s, t) = (u, v); linear filtering,
        repeating in s and clamped in t. The caller releases it.
    """
    data = np.asarray(image, dtype=np.float32)
    if data.ndim != 3 or data.shape[2] != 3:
        raise ValueError(f"lat-long image must have shape (h, w, 3), got {data.shape}")
    h, w = data.shape[:2]
    tex = ctx.texture((w, h), 3, np.ascontiguousarray(data).tobytes(), dtype="f4")
    tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
    tex.repeat_x, tex.repeat_y = True, False
    return tex


def latlong_to_cube(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    latlong_tex: moderngl.Texture,
    size: int,
    samples: int | None = None,
) -> moderngl.TextureCube:
    """Resample a lat-long texture into a mipmapped cube map.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    latlong_tex
        Lat-long texture as :func:`upload_latlong` makes it.
    size
        Face edge n in texels.
    samples
        k: each cube texel averages k × k bilinear samples (core.resample.latlong_to_cube);
        default core.resample.latlong_supersampling(h, n).

    Returns
    -------
    moderngl.TextureCube
        (n, n) RGBA32F, full mip chain built by ``build_mipmaps`` (a box filter per face),
        trilinear filtering. The caller releases it.
    """
    k = latlong_supersampling(latlong_tex.height, size) if samples is None else int(samples)
    if k < 1:
        raise ValueError(f"samples must be at least 1, got {samples}")
    return _to_cube(ctx, programs, _LATLONG, latlong_tex, size, {"u_samples": k})


def cube_to_latlong(
    ctx: moderngl.Context, programs: ProgramLibrary, cube_tex: moderngl.TextureCube, height: int
) -> moderngl.Texture:
    """Resample a cube map into a lat-long map.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    cube_tex
        Source cube map; its level 0 is read.
    height
        h in texels; the width is 2h.

    Returns
    -------
    moderngl.Texture
        (2h, h) RGBA32F, (s, t) = (u, v), repeating in s; the caller releases it.
    """
    return _to_2d(ctx, programs, _CUBE, cube_tex, (2 * height, height), {}, repeat_x=True)


def cube_to_paraboloid(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    cube_tex: moderngl.TextureCube,
    size: int,
    border: float = 0,
) -> moderngl.TextureArray:
    """Resample a cube map into a dual-paraboloid map.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    cube_tex
        Source cube map; its level 0 is read.
    size, border
        Face edge n and border B in texels (core.paraboloid); border texels hold the
        directions just beyond the rim.

    Returns
    -------
    moderngl.TextureArray
        (n, n, 2) RGBA32F, layer 0 front (z ≥ 0), layer 1 back; the caller releases it.
    """
    paraboloid.disc_scale(size, border)  # validates size and border
    target = ctx.texture_array((size, size, 2), 4, dtype="f4")
    target.filter = (moderngl.LINEAR, moderngl.LINEAR)
    target.repeat_x, target.repeat_y = False, False
    uniforms = {"u_target_border": float(border)}
    program = _program(programs, _CUBE, _PARABOLOID, cube_tex, (size, size), uniforms)

    def store(face: int, pixels: moderngl.Buffer) -> None:
        target.write(pixels, viewport=(0, 0, face, size, size, 1))

    _render_faces(ctx, program, size, 2, store)
    return target


def paraboloid_to_cube(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    paraboloid_tex: moderngl.TextureArray,
    size: int,
    border: float = 0,
) -> moderngl.TextureCube:
    """Resample a dual-paraboloid map into a mipmapped cube map.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    paraboloid_tex
        Source as :func:`cube_to_paraboloid` makes it.
    size
        Cube face edge n in texels.
    border
        Border B in texels of the source.

    Returns
    -------
    moderngl.TextureCube
        As :func:`latlong_to_cube` returns it.
    """
    paraboloid.disc_scale(paraboloid_tex.width, border)  # validates the border
    uniforms = {"u_source_border": float(border)}
    return _to_cube(ctx, programs, _PARABOLOID, paraboloid_tex, size, uniforms)


def cube_to_spheremap(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    cube_tex: moderngl.TextureCube,
    size: int,
    view_rotation: npt.ArrayLike | None = None,
) -> moderngl.Texture:
    """Resample a cube map into the sphere map a camera sees.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    cube_tex
        Source cube map; its level 0 is read.
    size
        Sphere map edge in texels.
    view_rotation
        (3, 3) float world-from-view rotation of the camera; default identity.

    Returns
    -------
    moderngl.Texture
        (n, n) RGBA32F, core.spheremap layout (row 0 = bottom of the ball); texels outside
        the disc hold the view −Z value. The caller releases it.
    """
    uniforms = {"u_view_rotation": spheremap.view_rotation_matrix(view_rotation)}
    return _to_2d(ctx, programs, _CUBE, cube_tex, (size, size), uniforms, repeat_x=False)


def spheremap_to_cube(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    spheremap_tex: moderngl.Texture,
    size: int,
    view_rotation: npt.ArrayLike | None = None,
) -> moderngl.TextureCube:
    """Resample a sphere map taken by a camera into a (world-space) mipmapped cube map.

    Parameters
    ----------
    ctx, programs
        Context and its program library.
    spheremap_tex
        Source sphere map, core.spheremap layout, clamped at its edges.
    size
        Cube face edge n in texels.
    view_rotation
        (3, 3) float world-from-view rotation of the camera; default identity.

    Returns
    -------
    moderngl.TextureCube
        As :func:`latlong_to_cube` returns it; directions near view −Z come from the
        stretched rim of the sphere map.
    """
    uniforms = {"u_view_rotation": spheremap.view_rotation_matrix(view_rotation)}
    return _to_cube(ctx, programs, _SPHEREMAP, spheremap_tex, size, uniforms)


def read_cube(
    tex: moderngl.TextureCube, level: int = 0, programs: ProgramLibrary | None = None
) -> npt.NDArray[np.float32]:
    """Read one mip level of a cube map back.

    Level 0 is read directly. moderngl reads back only level 0 of a cube map, so other
    levels are drawn: each texel centre is looked up with nearest filtering at exactly
    that level, which copies the texel.

    Parameters
    ----------
    tex
        Cube map with at least 3 components.
    level
        Mip level; its faces are m = n >> level texels wide.
    programs
        Program library of ``tex.ctx`` for levels above 0; a private one is made and
        released when omitted.

    Returns
    -------
    (6, m, m, 3) float32
        core.cubemap layout (OpenGL face order, rows ↔ t).
    """
    n = tex.size[0]
    if level < 0 or n >> level < 1:
        raise ValueError(f"cube map of size {n} has no mip level {level}")
    if level == 0:
        return np.stack(
            [_decode(tex.read(face), tex.dtype, (n, n, tex.components)) for face in range(6)]
        )
    library = ProgramLibrary(tex.ctx) if programs is None else programs
    try:
        return _read_cube_level(tex, level, library)
    finally:
        if programs is None:
            library.release()


def read_texture(tex: moderngl.Texture | moderngl.TextureArray) -> npt.NDArray[np.float32]:
    """Read level 0 of a 2D texture or texture array back.

    Parameters
    ----------
    tex
        Texture with at least 3 components (``f1`` data is scaled to [0, 1]).

    Returns
    -------
    (h, w, 3) or (layers, h, w, 3) float32
        Row 0 is t = 0 (for a lat-long map: +Y), as core's arrays.
    """
    if isinstance(tex, moderngl.TextureArray):
        w, h, layers = tex.size
        return _decode(tex.read(), tex.dtype, (layers, h, w, tex.components))
    w, h = tex.size
    return _decode(tex.read(), tex.dtype, (h, w, tex.components))


def save_latlong_exr(path: str | os.PathLike, tex: moderngl.Texture) -> Path:
    """Write a lat-long texture to an EXR file that io.images.read_environment reads back.

    Parameters
    ----------
    path
        Output file, ``.exr`` (half float, linear).
    tex
        Lat-long texture; row 0 (+Y) becomes the top row of the picture.

    Returns
    -------
    Path
        The file written.
    """
    return write_image(_exr(path), read_texture(tex))


def save_cube_exr(path: str | os.PathLike, tex: moderngl.TextureCube, level: int = 0) -> Path:
    """Write one mip level of a cube map to an EXR file as a horizontal cross.

    The (3m, 4m) picture is core.cubemap.faces_to_cross's layout (−X +Z +X −Z in the
    middle row, +Y above +Z, −Y below, each face with t growing downwards, unused
    blocks black); core.cubemap.cross_to_faces cuts it back into faces.

    Parameters
    ----------
    path
        Output file, ``.exr``.
    tex
        Cube map.
    level
        Mip level to write.

    Returns
    -------
    Path
        The file written.
    """
    return write_image(_exr(path), cubemap.faces_to_cross(read_cube(tex, level)))


def save_paraboloid_exr(path: str | os.PathLike, tex: moderngl.TextureArray) -> Path:
    """Write a dual-paraboloid map to an EXR file, front and back face side by side.

    The (n, 2n) picture has the front face (z ≥ 0) on the left and the back face on
    the right, each upright (t grows upwards, so the rows are flipped from the
    texture's order).

    Parameters
    ----------
    path
        Output file, ``.exr``.
    tex
        Dual-paraboloid map as :func:`cube_to_paraboloid` makes it.

    Returns
    -------
    Path
        The file written.
    """
    maps = read_texture(tex)
    return write_image(_exr(path), np.concatenate([maps[0][::-1], maps[1][::-1]], axis=1))


def save_spheremap_exr(path: str | os.PathLike, tex: moderngl.Texture) -> Path:
    """Write a sphere map to an EXR file, upright (rows flipped from the texture's order).

    Parameters
    ----------
    path
        Output file, ``.exr``.
    tex
        Sphere map texture, core.spheremap layout.

    Returns
    -------
    Path
        The file written: the mirror ball as the camera sees it, +Y at the top.
    """
    return write_image(_exr(path), read_texture(tex)[::-1])


def _to_cube(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    source_kind: int,
    source: moderngl.Texture | moderngl.TextureArray,
    size: int,
    uniforms: Mapping[str, object],
) -> moderngl.TextureCube:
    """Render the six faces of a new mipmapped cube map from ``source``."""
    if size < 1:
        raise ValueError(f"cube face size must be positive, got {size}")
    cube = ctx.texture_cube((size, size), 4, dtype="f4")
    program = _program(programs, source_kind, _CUBE, source, (size, size), uniforms)
    _render_faces(ctx, program, size, 6, cube.write)
    cube.build_mipmaps()
    cube.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
    return cube


def _to_2d(
    ctx: moderngl.Context,
    programs: ProgramLibrary,
    source_kind: int,
    source: moderngl.TextureCube,
    size: tuple[int, int],
    uniforms: Mapping[str, object],
    repeat_x: bool,
) -> moderngl.Texture:
    """Render a new RGBA32F 2D texture (lat-long or sphere map) from ``source``."""
    if min(size) < 1:
        raise ValueError(f"target size must be positive, got {size}")
    target_kind = _LATLONG if repeat_x else _SPHEREMAP
    target = ctx.texture(size, 4, dtype="f4")
    target.filter = (moderngl.LINEAR, moderngl.LINEAR)
    target.repeat_x, target.repeat_y = repeat_x, False
    program = _program(programs, source_kind, target_kind, source, size, uniforms)
    fbo = ctx.framebuffer([target])
    try:
        _draw_faces(ctx, program, fbo, 1, lambda face: None)
    finally:
        fbo.release()
    return target


def _read_cube_level(
    tex: moderngl.TextureCube, level: int, programs: ProgramLibrary
) -> npt.NDArray[np.float32]:
    ctx = tex.ctx
    m = tex.size[0] >> level
    nearest = ctx.sampler(filter=(moderngl.NEAREST_MIPMAP_NEAREST, moderngl.NEAREST), texture=tex)
    uniforms = {"u_source_lod": float(level)}
    program = _program(programs, _CUBE, _CUBE, tex, (m, m), uniforms)
    scratch = ctx.texture((m, m), 4, dtype="f4")
    fbo = ctx.framebuffer([scratch])
    faces = []

    def read(face: int) -> None:
        faces.append(_decode(fbo.read(components=4, dtype="f4"), "f4", (m, m, 4)))

    try:
        nearest.use(0)
        _draw_faces(ctx, program, fbo, 6, read)
    finally:
        nearest.clear(0)
        for obj in (fbo, scratch, nearest):
            obj.release()
    return np.stack(faces)


def _program(
    programs: ProgramLibrary,
    source_kind: int,
    target_kind: int,
    source: moderngl.Texture | moderngl.TextureArray | moderngl.TextureCube,
    target_size: tuple[int, int],
    uniforms: Mapping[str, object],
) -> moderngl.Program:
    """The resample program for a source/target pair, with source bound to unit 0."""
    program = programs.get(_RESAMPLE, {"SOURCE": source_kind, "TARGET": target_kind})
    values = {
        "u_source": 0,
        "u_source_lod": 0.0,
        "u_source_border": 0.0,
        "u_target_size": (float(target_size[0]), float(target_size[1])),
        "u_target_face": 0,
        "u_target_border": 0.0,
        "u_view_rotation": np.eye(3),
        "u_samples": 1,
        **uniforms,
    }
    for name, value in values.items():
        uniform = program.get(name, None)
        if uniform is None:
            continue  # optimised away: this source/target pair does not use it
        if name == "u_view_rotation":
            # GLSL reads matrices column-major; the transpose's rows are R's columns.
            uniform.write(np.ascontiguousarray(np.asarray(value).T, dtype=np.float32).tobytes())
        else:
            uniform.value = value
    source.use(0)
    return program


def _render_faces(
    ctx: moderngl.Context,
    program: moderngl.Program,
    size: int,
    count: int,
    store: Callable[[int, moderngl.Buffer], None],
) -> None:
    """Render faces 0 … count − 1 into a scratch (size, size) RGBA32F target, copying each
    into a pixel buffer handed to ``store(face, buffer)``, which writes it into place."""
    pixels = ctx.buffer(reserve=size * size * 16)
    scratch = ctx.texture((size, size), 4, dtype="f4")
    fbo = ctx.framebuffer([scratch])

    def copy(face: int) -> None:
        fbo.read_into(pixels, components=4, dtype="f4")
        store(face, pixels)

    try:
        _draw_faces(ctx, program, fbo, count, copy)
    finally:
        for obj in (fbo, scratch, pixels):
            obj.release()


def _draw_faces(
    ctx: moderngl.Context,
    program: moderngl.Program,
    fbo: moderngl.Framebuffer,
    count: int,
    after: Callable[[int], None],
) -> None:
    """Draw the full-screen pass into ``fbo`` for faces 0 … count − 1, calling ``after(face)``
    after each draw.

    Blending, depth test and culling are off for the passes; they and the framebuffer
    binding are restored afterwards.
    """
    quad = FullscreenPass(ctx)
    scope = ctx.scope(fbo, enable_only=moderngl.NOTHING)
    try:
        with scope:
            face_uniform = program.get("u_target_face", None)
            for face in range(count):
                if face_uniform is not None:
                    face_uniform.value = face
                quad.draw(program)
                after(face)
    finally:
        scope.release()
        quad.release()


def _decode(data: bytes, dtype: str, shape: tuple[int, ...]) -> npt.NDArray[np.float32]:
    """Texture bytes as float32 with the first 3 channels of the last axis."""
    if shape[-1] < 3:
        raise ValueError(f"texture has {shape[-1]} components, expected RGB or RGBA")
    pixels = np.frombuffer(data, dtype=_DTYPES[dtype]).reshape(shape)[..., :3]
    scale = 1.0 / 255.0 if dtype == "f1" else 1.0
    return (pixels.astype(np.float32) * np.float32(scale)).astype(np.float32)


def _exr(path: str | os.PathLike) -> Path:
    path = Path(path)
    if path.suffix.lower() != ".exr":
        raise InputFileError(f"{path}: expected an .exr file name for linear HDR output")
    return path
