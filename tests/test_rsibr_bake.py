"""Seed 002's radiance sphere maps: known values, lobe positions, the file (bake.rsibr)."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.core import latlong
from envstudio.envmap.conversions import latlong_to_cube, upload_latlong
from envstudio.errors import InputFileError, ParameterError
from envstudio.methods.rsibr.bake import bake as rb
from envstudio.methods.rsibr.gpu_bake import bake_gpu
from envstudio.methods.rsibr.warp import g_mirror_inverse, g_normal_inverse

SIZE = 32
RGB = np.array([0.25, 0.5, 2.0])


def _constant(height: int = 16) -> np.ndarray:
    return np.broadcast_to(RGB, (height, 2 * height, 3)).astype(np.float32)


def _bright_texel(height: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """A dim environment with one bright texel, and that texel's direction."""
    env = np.full((height, 2 * height, 3), 0.01, dtype=np.float32)
    row, col = 11, 21
    env[row, col] = 1000.0
    return env, latlong.texel_directions(height)[row, col]


def _peak(image: np.ndarray) -> np.ndarray:
    """(s, t) of the brightest texel."""
    i, j = np.unravel_index(np.argmax(image.sum(axis=-1)), image.shape[:2])
    return (np.array([j, i]) + 0.5) / image.shape[0]


def _gpu_bake(gl_ctx, programs, env, name, values=None):
    tex = upload_latlong(gl_ctx, env)
    cube = latlong_to_cube(gl_ctx, programs, tex, 32)
    try:
        return bake_gpu(gl_ctx, programs, cube, rb.environment_key(env), name, values, SIZE)
    finally:
        cube.release()
        tex.release()


@pytest.mark.parametrize("name", ["phong", "lambertian"])
def test_cpu_constant_environment_gives_constant_maps(name):
    bake = rb.bake_cpu(_constant(), name, {"phong_exponent": 20} if name == "phong" else {}, 16)
    assert bake.maps.shape == (12, 16, 16, 3)
    np.testing.assert_allclose(bake.maps, np.broadcast_to(RGB, bake.maps.shape), rtol=1e-6)


@pytest.mark.parametrize("name", ["phong", "lambertian"])
def test_gpu_constant_environment_gives_constant_maps(gl_ctx, programs, name):
    bake = _gpu_bake(gl_ctx, programs, _constant(), name)
    np.testing.assert_allclose(bake.maps, np.broadcast_to(RGB, bake.maps.shape), rtol=1e-5)


def _assert_lobes_in_place(bake: rb.RsibrBake, direction: np.ndarray) -> None:
    for frame, image in zip(bake.frames, bake.maps, strict=True):
        local = frame.T @ direction
        if bake.brdf == "phong":
            expected = g_mirror_inverse(local)
            if local[2] < -0.8:  # next to the singular rim the lobe is smeared around it
                continue
        else:
            if local[2] < 0.3:  # the lobe's peak must be on the visible hemisphere
                continue
            expected = g_normal_inverse(local)
        assert np.linalg.norm(_peak(image) - expected) <= 1.5 / bake.size, (local, bake.brdf)


@pytest.mark.parametrize("name", ["phong", "lambertian"])
def test_cpu_bright_texel_puts_the_lobe_where_each_frame_sees_it(name):
    env, direction = _bright_texel()
    bake = rb.bake_cpu(env, name, {"phong_exponent": 50} if name == "phong" else {}, SIZE)
    _assert_lobes_in_place(bake, direction)


def test_gpu_bright_texel_puts_the_lobe_where_each_frame_sees_it(gl_ctx, programs):
    env, direction = _bright_texel()
    _assert_lobes_in_place(_gpu_bake(gl_ctx, programs, env, "phong"), direction)


def test_gpu_and_cpu_bakes_agree(gl_ctx, programs):
    y = latlong.texel_directions(32)[..., 1]
    env = (0.2 + np.maximum(y, 0)[..., None] * [1.0, 0.8, 0.5]).astype(np.float32)
    for name in ("phong", "lambertian", "carpaint"):
        gpu = _gpu_bake(gl_ctx, programs, env, name, {})
        cpu = rb.bake_cpu(env, name, {}, SIZE)
        inside = (
            np.hypot(
                *np.meshgrid(np.arange(SIZE) + 0.5 - SIZE / 2, np.arange(SIZE) + 0.5 - SIZE / 2)
            )
            < 0.4 * SIZE
        )
        error = np.abs(gpu.maps - cpu.maps)[:, inside].mean() / cpu.maps[:, inside].mean()
        assert error < 0.02, (name, error)


def test_the_file_round_trips_and_refuses_bad_files(tmp_path):
    bake = rb.bake_cpu(_constant(8), "lambertian", {}, 8)
    path = rb.save_bake(tmp_path / "a.rsibr", bake)
    back = rb.load_bake(path, size=8)
    np.testing.assert_array_equal(back.maps, bake.maps)
    np.testing.assert_array_equal(back.faces, bake.faces)
    assert back.brdf == "lambertian" and back.warp == "normal"
    with pytest.raises(InputFileError, match="expected 16²"):
        rb.load_bake(path, size=16)
    tampered = dict(np.load(path))
    tampered["maps"] = tampered["maps"] * 2
    np.savez(tmp_path / "b.rsibr.npz", **tampered)
    with pytest.raises(InputFileError, match="checksum"):
        rb.load_bake(tmp_path / "b.rsibr.npz")
    short = rb.RsibrBake(**{**vars(bake), "maps": bake.maps[:11]})
    rb.save_bake(tmp_path / "c.rsibr", short)
    with pytest.raises(InputFileError, match="views are missing"):
        rb.load_bake(tmp_path / "c.rsibr")
    (tmp_path / "d.rsibr").write_bytes(b"not a zip")
    with pytest.raises(InputFileError, match="not a readable"):
        rb.load_bake(tmp_path / "d.rsibr")
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "a.rsibr",
        "b.rsibr.npz",
        "c.rsibr",
        "d.rsibr",
    ]  # no temporary left behind


def test_parameters_are_checked():
    with pytest.raises(ParameterError, match="phong_exponent"):
        rb.bake_cpu(_constant(8), "phong", {"phong_exponent": 0}, 8)
    with pytest.raises(ParameterError, match="unknown BRDF"):
        rb.bake_cpu(_constant(8), "ward", {}, 8)
