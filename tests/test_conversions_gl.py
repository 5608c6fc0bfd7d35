"""GLSL parameterizations and GPU conversions against the NumPy reference (EGL, small sizes).

Tolerances. Directions, texture coordinates and solid angles are float32 GLSL against
float64 NumPy: a few float32 ulps of values of order 1. Conversions compare filtered
lookups: GPUs blend bilinear taps with weights of 8 fractional bits (the sub-texel
precision GL implementations, llvmpipe included, provide), so a lookup may differ from
exact bilinear by up to 2^-8 of the local range of the source; that plus float32 rounding
is the bound used. Lookups within half a texel of a cube corner are left out where a
driver may build the missing fourth texel differently (core.resample).
"""

from __future__ import annotations

import moderngl
import numpy as np
import pytest

from envstudio.core import cubemap, latlong, paraboloid, resample, sh, spheremap
from envstudio.envmap import conversions as cv
from envstudio.errors import InputFileError
from envstudio.gpu.fullscreen import FullscreenPass
from envstudio.gpu.programs import read_shader
from envstudio.gpu.shader_source import preprocess
from envstudio.io.images import read_environment, read_image, write_image

MAPS = {"latlong": 0, "cube": 1, "paraboloid": 2, "spheremap": 3}

DIRECTION_PROGRAM = """
#include "common/latlong.glsl"
#include "common/cubemap.glsl"
#include "common/paraboloid.glsl"
#include "common/spheremap.glsl"
uniform ivec2 u_size;
uniform int u_face;
uniform float u_border;
out vec4 frag_color;
void main() {
    ivec2 texel = ivec2(gl_FragCoord.xy);
    vec2 uv = (vec2(texel) + 0.5) / vec2(u_size);
    float n = float(u_size.x);
#if MAP == 0
    frag_color = vec4(latlong_direction(uv), latlong_texel_solid_angle(texel, u_size));
#elif MAP == 1
    frag_color = vec4(cube_face_direction(u_face, uv), cube_texel_solid_angle(texel, u_size.x));
#elif MAP == 2
    frag_color = vec4(paraboloid_direction(u_face, uv, n, u_border),
                      paraboloid_texel_solid_angle(texel, n, u_border));
#else
    frag_color = vec4(spheremap_direction(uv), spheremap_texel_solid_angle(texel, u_size.x));
#endif
}
"""

UV_PROGRAM = """
#include "common/latlong.glsl"
#include "common/cubemap.glsl"
#include "common/paraboloid.glsl"
#include "common/spheremap.glsl"
#include "common/sh.glsl"
uniform sampler2D u_directions;
uniform float u_size;
uniform float u_border;
uniform vec3 u_coeffs[9];
out vec4 frag_color;
void main() {
    vec3 d = texelFetch(u_directions, ivec2(gl_FragCoord.xy), 0).xyz;
    int face = 0;
#if MAP == 0
    frag_color = vec4(latlong_uv(d), 0.0, 0.0);
#elif MAP == 1
    vec2 uv = cube_face_uv(d, face);
    frag_color = vec4(uv, float(face), 0.0);
#elif MAP == 2
    vec2 uv = paraboloid_uv(d, u_size, u_border, face);
    frag_color = vec4(uv, float(face), 0.0);
#elif MAP == 3
    frag_color = vec4(spheremap_uv(d), 0.0, 0.0);
#else
    frag_color = vec4(sh9_irradiance(u_coeffs, d), 0.0);
#endif
}
"""


def fibonacci_directions(count: int) -> np.ndarray:
    i = np.arange(count) + 0.5
    y = 1.0 - 2.0 * i / count
    phi = np.pi * (3.0 - np.sqrt(5.0)) * i
    r = np.sqrt(1.0 - y * y)
    return np.stack([r * np.cos(phi), y, r * np.sin(phi)], axis=-1)


def compile_test_program(ctx, body: str, defines) -> moderngl.Program:
    """A full-screen program whose fragment stage is ``body`` (may include common/ files)."""
    name = "tests/program.glsl"
    text = (
        "#version 330 core\n#if defined VERTEX_SHADER\n"
        '#include "common/fullscreen_vs.glsl"\n#elif defined FRAGMENT_SHADER\n'
        f"{body}\n#endif\n"
    )

    def read(path):
        return text if path == name else read_shader(path)

    vertex, _ = preprocess(name, "VERTEX_SHADER", read, defines)
    fragment, _ = preprocess(name, "FRAGMENT_SHADER", read, defines)
    return ctx.program(vertex_shader=vertex, fragment_shader=fragment)


def render(ctx, program, width: int, height: int) -> np.ndarray:
    """Draw ``program`` into a (width, height) RGBA32F target; (height, width, 4), row 0 = t = 0."""
    target = ctx.texture((width, height), 4, dtype="f4")
    fbo = ctx.framebuffer([target])
    quad = FullscreenPass(ctx)
    fbo.use()
    quad.draw(program)
    pixels = np.frombuffer(fbo.read(components=4, dtype="f4"), np.float32)
    quad.release()
    fbo.release()
    target.release()
    return pixels.reshape(height, width, 4).astype(np.float64)


def upload_cube(ctx, faces: np.ndarray) -> moderngl.TextureCube:
    n = faces.shape[1]
    tex = ctx.texture_cube((n, n), 3, dtype="f4")
    for face in range(6):
        tex.write(face, np.ascontiguousarray(faces[face], dtype=np.float32).tobytes())
    tex.build_mipmaps()
    tex.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
    return tex


def filter_tolerance(source: np.ndarray) -> float:
    """2^-8 of the source's range (8-bit bilinear weights) plus float32 rounding."""
    return float(np.ptp(source)) / 256.0 + 1e-5 * float(np.abs(source).max())


def away_from_cube_corners(directions: np.ndarray, n: int) -> np.ndarray:
    """True where a bilinear cube lookup does not touch a corner's synthesised texel."""
    _, uv = cubemap.direction_to_uv(directions)
    near_edge = np.minimum(uv, 1.0 - uv) < 0.5 / n
    return ~(near_edge[..., 0] & near_edge[..., 1])


@pytest.mark.parametrize("name", list(MAPS))
def test_glsl_directions_and_solid_angles_match_numpy(gl_ctx, name):
    program = compile_test_program(gl_ctx, DIRECTION_PROGRAM, {"MAP": MAPS[name]})
    n, border = 12, 1.5
    if name == "latlong":
        expected = [(latlong.texel_directions(n, 2 * n), latlong.texel_solid_angles(n, 2 * n))]
        size = (2 * n, n)
    elif name == "cube":
        expected = zip(cubemap.texel_directions(n), cubemap.texel_solid_angles(n), strict=True)
        size = (n, n)
    elif name == "paraboloid":
        dirs, angles = (
            paraboloid.texel_directions(n, border),
            paraboloid.texel_solid_angles(n, border),
        )
        expected = zip(dirs, angles, strict=True)
        size = (n, n)
    else:
        expected = [(spheremap.texel_directions(n), spheremap.texel_solid_angles(n))]
        size = (n, n)
    program["u_size"] = size
    if "u_border" in program:
        program["u_border"] = border
    for face, (dirs, angles) in enumerate(expected):
        if "u_face" in program:
            program["u_face"] = face
        out = render(gl_ctx, program, *size)
        np.testing.assert_allclose(out[..., :3], dirs, atol=1e-5)
        np.testing.assert_allclose(out[..., 3], angles, rtol=1e-4, atol=1e-7)


@pytest.mark.parametrize("name", [*MAPS, "sh"])
def test_glsl_texture_coordinates_and_sh_match_numpy(gl_ctx, name):
    side = 64
    dirs = fibonacci_directions(side * side).astype(np.float32).astype(np.float64)
    if name == "spheremap":  # leave out the singular neighbourhood of view -Z
        dirs = dirs[dirs[:, 2] > -0.999][: 62 * side]
    height = len(dirs) // side
    dirs = dirs[: height * side].reshape(height, side, 3)
    tex = gl_ctx.texture((side, height), 3, dirs.astype(np.float32).tobytes(), dtype="f4")
    tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
    program = compile_test_program(gl_ctx, UV_PROGRAM, {"MAP": MAPS.get(name, 4)})
    size, border = 32, 2
    for uniform, value in (("u_size", size), ("u_border", border), ("u_directions", 0)):
        if uniform in program:
            program[uniform] = value
    tex.use(0)
    if name == "sh":
        coeffs = np.random.default_rng(5).normal(size=(9, 3))
        program["u_coeffs"].write(coeffs.astype(np.float32).tobytes())
    out = render(gl_ctx, program, side, height)
    if name == "latlong":
        du = np.abs(out[..., 0] - latlong.direction_to_uv(dirs)[..., 0])
        assert np.minimum(du, 1.0 - du).max() < 1e-5  # u wraps at the +Z seam
        np.testing.assert_allclose(out[..., 1], latlong.direction_to_uv(dirs)[..., 1], atol=1e-5)
    elif name == "cube":
        face, uv = cubemap.direction_to_uv(dirs)
        np.testing.assert_array_equal(out[..., 2], face)
        np.testing.assert_allclose(out[..., :2], uv, atol=1e-5)
    elif name == "paraboloid":
        face, uv = paraboloid.direction_to_uv(dirs, size, border)
        np.testing.assert_array_equal(out[..., 2], face)
        np.testing.assert_allclose(out[..., :2], uv, atol=1e-5)
    elif name == "spheremap":
        np.testing.assert_allclose(out[..., :2], spheremap.direction_to_uv(dirs), atol=1e-5)
    else:
        expected = sh.irradiance_sh9(coeffs, dirs)
        np.testing.assert_allclose(out[..., :3], expected, atol=1e-5 * np.abs(expected).max())


@pytest.mark.parametrize("samples", [1, 2])
def test_latlong_to_cube_matches_numpy(gl_ctx, programs, samples):
    image = np.random.default_rng(2).random((24, 48, 3)).astype(np.float32)
    image[3, 5] = 40.0  # an HDR highlight
    latlong_tex = cv.upload_latlong(gl_ctx, image)
    cube = cv.latlong_to_cube(gl_ctx, programs, latlong_tex, 16, samples=samples)
    assert cube.size == (16, 16)
    np.testing.assert_allclose(
        cv.read_cube(cube),
        resample.latlong_to_cube(image, 16, samples=samples),
        atol=filter_tolerance(image),
    )


def test_conversions_from_a_cube_match_numpy(gl_ctx, programs):
    n = 16
    faces = np.random.default_rng(4).random((6, n, n, 3)).astype(np.float32)
    cube = upload_cube(gl_ctx, faces)
    tol = filter_tolerance(faces)
    caller_target = gl_ctx.texture((4, 4), 4, dtype="f4")
    caller_fbo = gl_ctx.framebuffer([caller_target])
    caller_fbo.use()

    out = cv.read_texture(cv.cube_to_latlong(gl_ctx, programs, cube, 24))
    keep = away_from_cube_corners(latlong.texel_directions(24), n)
    np.testing.assert_allclose(out[keep], resample.cube_to_latlong(faces, 24)[keep], atol=tol)

    size, border = 20, 2
    out = cv.read_texture(cv.cube_to_paraboloid(gl_ctx, programs, cube, size, border))
    assert out.shape == (2, size, size, 3)
    keep = away_from_cube_corners(paraboloid.texel_directions(size, border), n)
    expected = resample.cube_to_paraboloid(faces, size, border)
    np.testing.assert_allclose(out[keep], expected[keep], atol=tol)

    angle = 0.7
    R = np.array([[1, 0, 0], [0, np.cos(angle), -np.sin(angle)], [0, np.sin(angle), np.cos(angle)]])
    out = cv.read_texture(cv.cube_to_spheremap(gl_ctx, programs, cube, 24, R))
    keep = away_from_cube_corners(spheremap.texel_directions(24) @ R.T, n)
    expected = resample.cube_to_spheremap(faces, 24, R)
    np.testing.assert_allclose(out[keep], expected[keep], atol=tol)

    # The passes restore the caller's framebuffer: a draw now lands in it.
    fill = compile_test_program(gl_ctx, "out vec4 c;\nvoid main() { c = vec4(0.25); }", {})
    FullscreenPass(gl_ctx).draw(fill)
    np.testing.assert_array_equal(np.frombuffer(caller_target.read(), np.float32), 0.25)


def test_conversions_to_a_cube_match_numpy(gl_ctx, programs):
    rng = np.random.default_rng(6)
    size, border, n = 20, 2, 12
    maps = rng.random((2, size, size, 3)).astype(np.float32)
    array = gl_ctx.texture_array((size, size, 2), 3, maps.tobytes(), dtype="f4")
    array.filter = (moderngl.LINEAR, moderngl.LINEAR)
    array.repeat_x, array.repeat_y = False, False
    out = cv.read_cube(cv.paraboloid_to_cube(gl_ctx, programs, array, n, border))
    expected = resample.paraboloid_to_cube(maps, n, border)
    np.testing.assert_allclose(out, expected, atol=filter_tolerance(maps))

    image = rng.random((24, 24, 3)).astype(np.float32)
    sphere = gl_ctx.texture((24, 24), 3, image.tobytes(), dtype="f4")
    sphere.repeat_x, sphere.repeat_y = False, False
    R = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]], dtype=float)
    out = cv.read_cube(cv.spheremap_to_cube(gl_ctx, programs, sphere, n, R))
    # Near view -Z the sphere-map coordinates are ill-conditioned in float32 (the rim).
    keep = cubemap.texel_directions(n) @ R[:, 2] > -0.95
    expected = resample.spheremap_to_cube(image, n, R)
    np.testing.assert_allclose(out[keep], expected[keep], atol=filter_tolerance(image))


def test_cube_mip_chain_is_the_box_filtered_face(gl_ctx, programs):
    n = 16
    faces = np.random.default_rng(8).random((6, n, n, 3)).astype(np.float32)
    faces[2, 0, 0] = 100.0
    image = resample.cube_to_latlong(faces, 32)
    cube = cv.latlong_to_cube(gl_ctx, programs, cv.upload_latlong(gl_ctx, image), n)
    level0 = cv.read_cube(cube)
    top = cv.read_cube(cube, level=4, programs=programs)
    assert top.shape == (6, 1, 1, 3)
    np.testing.assert_allclose(top[:, 0, 0], level0.mean(axis=(1, 2)), rtol=1e-5)
    level1 = cv.read_cube(cube, level=1)  # with a private program library
    box = level0.reshape(6, n // 2, 2, n // 2, 2, 3).mean(axis=(2, 4))
    np.testing.assert_allclose(level1, box, rtol=1e-5, atol=1e-6)
    with pytest.raises(ValueError, match="no mip level 5"):
        cv.read_cube(cube, level=5)


def test_saved_exr_files_read_back_equal(gl_ctx, programs, tmp_path):
    rng = np.random.default_rng(9)
    image = rng.random((16, 32, 3)).astype(np.float32) * 4.0
    latlong_tex = cv.upload_latlong(gl_ctx, image)
    cube = cv.latlong_to_cube(gl_ctx, programs, latlong_tex, 8)

    def half(a):
        return a.astype(np.float16).astype(np.float32)

    cv.save_latlong_exr(tmp_path / "latlong.exr", latlong_tex)
    np.testing.assert_array_equal(read_environment(tmp_path / "latlong.exr"), half(image))

    cv.save_cube_exr(tmp_path / "cube.exr", cube)
    cross = read_image(tmp_path / "cube.exr")
    assert cross.shape == (24, 32, 3)
    np.testing.assert_array_equal(cubemap.cross_to_faces(cross), half(cv.read_cube(cube)))

    para = cv.cube_to_paraboloid(gl_ctx, programs, cube, 8, 1)
    cv.save_paraboloid_exr(tmp_path / "paraboloid.exr", para)
    maps = cv.read_texture(para)
    side_by_side = read_image(tmp_path / "paraboloid.exr")
    np.testing.assert_array_equal(side_by_side[:, :8], half(maps[0][::-1]))
    np.testing.assert_array_equal(side_by_side[:, 8:], half(maps[1][::-1]))

    sphere = cv.cube_to_spheremap(gl_ctx, programs, cube, 8)
    cv.save_spheremap_exr(tmp_path / "sphere.exr", sphere)
    upright = read_image(tmp_path / "sphere.exr")
    np.testing.assert_array_equal(upright[::-1], half(cv.read_texture(sphere)))

    with pytest.raises(InputFileError, match=r"\.exr"):
        cv.save_spheremap_exr(tmp_path / "sphere.png", sphere)


def test_latlong_file_survives_the_gpu_round_trip(gl_ctx, programs, tmp_path):
    """File (row 0 = +Y) -> texture -> cube -> lat-long -> file keeps its orientation."""

    def radiance(d):
        return np.stack([1.0 + d[..., 1], 1.0 + 0.5 * d[..., 0], 1.0 - 0.5 * d[..., 2]], axis=-1)

    image = radiance(latlong.texel_directions(32))
    write_image(tmp_path / "in.exr", image)
    source = read_environment(tmp_path / "in.exr")
    cube = cv.latlong_to_cube(gl_ctx, programs, cv.upload_latlong(gl_ctx, source), 32)
    # Each face shows its own side of the field: +Y is bright in red, -X dark in green, ...
    expected = radiance(cubemap.texel_directions(32))
    np.testing.assert_allclose(cv.read_cube(cube), expected, atol=5e-3)
    cv.save_latlong_exr(tmp_path / "out.exr", cv.cube_to_latlong(gl_ctx, programs, cube, 32))
    np.testing.assert_allclose(read_environment(tmp_path / "out.exr"), source, atol=5e-3)
