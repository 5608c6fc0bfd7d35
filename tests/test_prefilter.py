"""CPU prefilter (seed 004 §4, §5.1): kernels, brute force, hierarchical, the command."""

from __future__ import annotations

import json
import os
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from scipy import ndimage

from envstudio.cli import main
from envstudio.core import cubemap, latlong
from envstudio.io.dds import write_dds_cube
from envstudio.io.images import read_environment, read_image
from envstudio.prefilter import brute_force, hierarchical, kernels, spectral
from envstudio.prefilter.bench import run_prefilter_bench, write_scaling_plot
from envstudio.prefilter.chain import gloss_exponents, prefiltered_chain
from envstudio.prefilter.targets import target_directions, target_picture
from envstudio.resources import asset_root

SUNRISE = str(asset_root() / "hdr" / "sunrise.exr")


def smooth_map(height: int, seed: int) -> np.ndarray:
    """A positive, smooth random lat-long map: exp of a random low-order polynomial of d."""
    rng = np.random.default_rng(seed)
    d = latlong.texel_directions(height)
    a, b = rng.normal(size=(2, 3, 3))
    poly = d @ a + 0.7 * (d @ b) ** 2
    return np.exp(poly).astype(np.float32)


def unit_vectors(n: int, seed: int) -> np.ndarray:
    v = np.random.default_rng(seed).normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@pytest.fixture(scope="module")
def sunrise_32() -> np.ndarray:
    return brute_force.downsample_latlong(read_environment(SUNRISE), 32)


def lobe_kernel() -> kernels.Kernel:
    """A non-monotone lobe (a peak and an off-specular bump) to exercise the table path."""
    c = np.array([-1.0, 0.0, 0.5, 0.7, 0.8, 0.95, 1.0])
    p = np.array([0.0, 0.0, 0.0, 0.6, 0.1, 0.5, 3.0])
    return kernels.lobe(c, p)


# --- kernels ---------------------------------------------------------------------------------


def test_kernel_values():
    c = np.linspace(-1, 1, 101)
    phong = kernels.phong(20.0)
    assert np.allclose(phong(c), 21 / (2 * np.pi) * np.maximum(c, 0) ** 20, rtol=1e-5, atol=1e-9)
    diffuse = kernels.diffuse(0.5)
    assert np.allclose(diffuse(c), 0.5 / np.pi * np.maximum(c, 0), rtol=1e-6)
    lobe = lobe_kernel()
    table = np.interp(c, [-1, 0, 0.5, 0.7, 0.8, 0.95, 1], [0, 0, 0, 0.6, 0.1, 0.5, 3.0])
    assert np.allclose(lobe(c), table, atol=2e-3)


@pytest.mark.parametrize("kernel", [kernels.phong(50.0), kernels.diffuse(), lobe_kernel()])
def test_spread_bounds_the_kernel_on_every_interval(kernel):
    rng = np.random.default_rng(3)
    ends = np.sort(rng.uniform(-1, 1, size=(200, 2)), axis=1).astype(np.float32)
    spread = kernel.spread(ends[:, 0].copy(), ends[:, 1].copy())
    inside = ends[:, :1] + (ends[:, 1:] - ends[:, :1]) * np.linspace(0, 1, 400)
    values = kernel.shape(inside)
    assert np.all(spread >= values.max(axis=1) - values.min(axis=1) - 1e-5)  # float32 c^N


# --- brute force -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kernel", "expected"),
    [(kernels.phong(8.0), 1.0), (kernels.diffuse(0.6), 0.6), (kernels.phong(1.0), 1.0)],
)
def test_brute_force_constant_environment(kernel, expected):
    """A constant L gives L for the normalised Phong lobe and k_d L for diffuse (quadrature)."""
    image = np.full((64, 128, 3), 2.0, np.float32)
    out = brute_force.prefilter(image, unit_vectors(50, 1), kernel, threads=2)
    assert np.allclose(out, 2.0 * expected, rtol=2e-3)


def test_brute_force_single_texel_is_the_kernel():
    """One bright texel: the filtered cube is the kernel centred on its direction."""
    image = np.zeros((16, 32, 3), np.float32)
    image[5, 11] = (1.0, 2.0, 3.0)
    kernel = kernels.phong(6.0)
    out = brute_force.prefilter(image, cubemap.texel_directions(8), kernel)
    bright = latlong.texel_directions(16)[5, 11]
    solid = latlong.texel_solid_angles(16)[5, 11]
    expected = kernel(cubemap.texel_directions(8) @ bright)[..., None] * solid * np.array([1, 2, 3])
    assert np.allclose(out, expected, rtol=1e-4, atol=1e-7)


@pytest.mark.parametrize("exponent", [3.0, 60.0, 400.0])
def test_brute_force_matches_an_independent_float64_sum(exponent):
    image = smooth_map(32, seed=int(exponent))
    queries = unit_vectors(7, 2)
    out = brute_force.prefilter(image, queries, kernels.phong(exponent))
    d = latlong.texel_directions(32).reshape(-1, 3)
    weights = latlong.texel_solid_angles(32).reshape(-1)
    for q, got in zip(queries, out, strict=True):
        lobe = (exponent + 1) / (2 * np.pi) * np.power(np.maximum(d @ q, 0.0), exponent)
        truth = np.einsum("s,s,sc->c", lobe, weights, image.reshape(-1, 3).astype(np.float64))
        assert np.allclose(got, truth, rtol=2e-4), (got, truth)


@pytest.mark.parametrize(
    "kernel",
    [
        kernels.phong(500.0),
        kernels.phong(10.0),
        kernels.phong(2.0),
        kernels.phong(1.5),
        kernels.phong(0.5),
        kernels.diffuse(),
    ],
)
def test_derivative_bounds_hold_on_every_interval(kernel):
    """Kernel.derivative_bound bounds the first three derivatives of k̂ on every interval."""
    rng = np.random.default_rng(4)
    ends = np.sort(rng.uniform(-1, 1, size=(300, 2)), axis=1).astype(np.float32)
    ends[:100] = np.sort(rng.uniform(0.9, 1, size=(100, 2)), axis=1)  # where the lobe is
    n = kernel.exponent
    inside = ends[:, :1] + (ends[:, 1:] - ends[:, :1]) * np.linspace(0, 1, 400)
    c, lit = np.clip(inside, 1e-12, None), inside > 0
    for order in (1, 2, 3):
        bound = kernel.derivative_bound(ends[:, 0], ends[:, 1], order)
        factor = abs(float(np.prod([n - k for k in range(order)])))
        exact = np.where(lit, factor * c ** (n - order), 0.0).max(axis=1)
        assert np.all(bound >= exact * (1 - 1e-4) - 1e-6), order
    lobe = kernels.lobe([0, 1], [0, 1])
    assert np.all(np.isinf(lobe.derivative_bound(ends[:, 0], ends[:, 1], 2)))


# --- hierarchical ----------------------------------------------------------------------------


def relative_max_difference(a, b) -> float:
    return float(np.abs(a - b).max() / b.mean())


@pytest.mark.parametrize("param", ["paraboloid", "cube"])
@pytest.mark.parametrize("exponent", [10.0, 200.0])
def test_hierarchical_matches_brute_force_on_smooth_maps(param, exponent):
    image = smooth_map(64, seed=7)
    directions = target_directions(param, 16)
    kernel = kernels.phong(exponent)
    brute = brute_force.prefilter(image, directions, kernel)
    hier = hierarchical.prefilter(image, directions, kernel, 1e-3)
    assert relative_max_difference(hier, brute) < 0.002


@pytest.mark.parametrize("kernel", [kernels.diffuse(), lobe_kernel(), kernels.phong(500.0)])
def test_hierarchical_matches_brute_force_on_sunrise(sunrise_32, kernel):
    """A sun-dominated map: within 1 % of the map's mean (the bench's criterion)."""
    directions = target_directions("paraboloid", 16, 2)
    brute = brute_force.prefilter(sunrise_32, directions, kernel)
    hier = hierarchical.prefilter(sunrise_32, directions, kernel, 1e-3, tile=4)
    assert relative_max_difference(hier, brute) < 0.01


@pytest.mark.parametrize(
    "kernel",
    [kernels.phong(0.5), kernels.phong(1.5), kernels.phong(2.5), kernels.diffuse(), lobe_kernel()],
)
def test_hierarchical_on_a_constant_map_without_warnings(kernel):
    """Exponents where k̂'s derivatives are unbounded at c = 0 take no Taylor step there."""
    image = np.full((32, 64, 3), 2.0, np.float32)
    directions = target_directions("cube", 8)
    brute = brute_force.prefilter(image, directions, kernel)
    with np.errstate(all="raise"):
        hier = hierarchical.prefilter(image, directions, kernel, 1e-3, threads=1)
    assert relative_max_difference(hier, brute) < 1e-3


def test_hierarchical_threshold_trades_accuracy():
    image = smooth_map(64, seed=11)
    directions = target_directions("cube", 8)
    kernel = kernels.phong(50.0)
    brute = brute_force.prefilter(image, directions, kernel)
    loose = hierarchical.prefilter(image, directions, kernel, 0.05)
    tight = hierarchical.prefilter(image, directions, kernel, 1e-4)
    assert relative_max_difference(tight, brute) < relative_max_difference(loose, brute)
    assert relative_max_difference(tight, brute) < 2e-4


def test_pyramid_radii_bound_every_texel():
    pyramid = hierarchical.source_pyramid(smooth_map(16, 0))
    fine = pyramid.directions[0]
    for level in range(1, pyramid.top + 1):
        h, w = pyramid.shapes[level]
        f = 2**level
        texels = fine.reshape(3, h, f, w, f)
        d = pyramid.directions[level].reshape(3, h, 1, w, 1)
        cos = np.clip(np.sum(texels * d, axis=0), -1, 1)
        angle = np.arccos(cos).max(axis=(1, 3)).reshape(-1)
        assert np.all(angle <= np.arccos(pyramid.radii[level][0]) + 1e-4)


def test_pyramid_moments_match_their_texels():
    """Each node's centroid, second moment and residual, summed directly over its texels."""
    image = smooth_map(16, 2) * np.array([1.0, 0.5, 2.0], np.float32)  # coloured: a_n > 0
    image[3, 5] = 400.0  # a bright texel
    pyramid = hierarchical.source_pyramid(image)
    dirs = latlong.texel_directions(16).reshape(-1, 3)
    weights = image.reshape(-1, 3) * latlong.texel_solid_angles(16).reshape(-1, 1)
    for level in range(1, pyramid.top + 1):
        h, w = pyramid.shapes[level]
        f = 2**level
        rows, cols = np.divmod(np.arange(16 * 32), 32)
        node = (rows // f) * w + cols // f
        for n in (0, h * w // 2, h * w - 1, (3 // f) * w + 5 // f):
            mine = node == n
            d, ws = dirs[mine], weights[mine]
            total = ws.sum(axis=1)
            centroid = (d * total[:, None]).sum(axis=0) / total.sum()
            assert np.allclose(pyramid.samples[level][:, n], centroid, atol=1e-6)
            r = unit_vectors(5, n)
            quad = ((((d - centroid) @ r.T) ** 2) * total[:, None]).sum(axis=0) / total.sum()
            pairs = np.stack([r[:, a] * r[:, b] for a, b in hierarchical._PAIRS], axis=1)
            assert np.allclose(pairs @ pyramid.spreads[level][:, n], quad, rtol=1e-4, atol=1e-9)
            dipole = (d - centroid).T @ ws
            assert np.allclose(pyramid.dipoles[level][n], dipole.reshape(-1), rtol=1e-3, atol=1e-9)
            size = np.linalg.norm(dipole, axis=0) / ws.sum(axis=0)
            assert pyramid.residuals[level][n] == pytest.approx(size.max(), rel=1e-4, abs=1e-9)


def test_hierarchical_taylor_bound_on_a_wide_lobe():
    """N = 10, where the spread test alone sends the whole lobe to texels: still within T."""
    image = brute_force.downsample_latlong(read_environment(SUNRISE), 64)
    directions = target_directions("cube", 16)
    kernel = kernels.phong(10.0)
    brute = brute_force.prefilter(image, directions, kernel)
    hier = hierarchical.prefilter(image, directions, kernel, 1e-3)
    assert relative_max_difference(hier, brute) < 0.002


# --- the command -----------------------------------------------------------------------------


def test_prefilter_command_writes_the_map(tmp_path, capsys):
    out = tmp_path / "para.exr"
    status = main(
        ["prefilter", "--env", SUNRISE, "--exponent", "20", "--algo", "brute", "--size", "8",
         "--border", "1", "--source-height", "32", "-o", str(out)]
    )  # fmt: skip
    assert status == 0 and out.exists()
    picture = read_image(out)
    source = brute_force.downsample_latlong(read_environment(SUNRISE), 32)
    maps = brute_force.prefilter(source, target_directions("paraboloid", 8, 1), kernels.phong(20))
    assert picture.shape == (8, 16, 3)
    assert np.allclose(picture, target_picture("paraboloid", maps), rtol=2e-3, atol=1e-4)


def test_prefilter_command_cube_cross_and_lobe(tmp_path):
    table = tmp_path / "lobe.csv"
    table.write_text("cos,p\n0.5,0\n0.9,0.5\n1.0,4\n")
    out = tmp_path / "cube.exr"
    argv = ["prefilter", "--env", SUNRISE, "--kernel", "lobe", "--lobe", str(table), "--param",
            "cube", "--size", "4", "--source-height", "16", "-o", str(out)]  # fmt: skip
    assert main(argv) == 0
    assert read_image(out).shape == (12, 16, 3)


def assert_one_line_error(status, err, *fragments):
    assert status == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


@pytest.mark.parametrize(
    ("extra", "fragments"),
    [
        (["--exponent", "0"], ["--exponent 0", "(0, 100000]"]),
        (["--exponent", "-3"], ["--exponent -3"]),
        ([], ["--exponent N"]),
        (["--exponent", "10", "--threshold", "0"], ["--threshold 0", "(0, 1)"]),
        (["--exponent", "10", "--threshold", "1.5"], ["--threshold 1.5", "(0, 1)"]),
        (["--exponent", "10", "--size", "8", "--border", "4"], ["--border 4", "size/2 = 4"]),
        (["--exponent", "10", "--param", "cube", "--border", "2"], ["--border 2", "paraboloid"]),
        (["--exponent", "10", "--size", "20000"], ["--size 20000", "1..16384"]),
        (["--exponent", "10", "--param", "cube", "--size", "16384"], ["MiB", "free"]),
        (["--exponent", "10", "--source-height", "100"], ["--source-height 100", "divisor"]),
        (["--kernel", "lobe"], ["--lobe TABLE.csv"]),
        (["--kernel", "diffuse", "--kd", "2"], ["--kd 2", "(0, 1]"]),
    ],
)
def test_prefilter_bad_input(tmp_path, capsys, extra, fragments):
    argv = ["prefilter", "--env", SUNRISE, *extra, "-o", str(tmp_path / "out.exr")]
    status = main(argv)
    assert_one_line_error(status, capsys.readouterr().err, *fragments)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("rows", "fragments"),
    [
        ("1.0,2.0\n", ["at least 2 rows"]),
        ("0.5,1\n0.2,2\n1.0,3\n", ["increase strictly"]),
        ("0.5,1\n0.5,2\n", ["increase strictly"]),
        ("0.5,-1\n1.0,2\n", ["finite, >= 0"]),
        ("0.5,1\nabc,2\n", ["line 2"]),
    ],
)
def test_prefilter_bad_lobe_table(tmp_path, capsys, rows, fragments):
    table = tmp_path / "lobe.csv"
    table.write_text(rows)
    argv = ["prefilter", "--env", SUNRISE, "--kernel", "lobe", "--lobe", str(table),
            "-o", str(tmp_path / "out.exr")]  # fmt: skip
    assert_one_line_error(main(argv), capsys.readouterr().err, str(table), *fragments)
    assert not (tmp_path / "out.exr").exists()


def test_ctrl_c_leaves_no_file(tmp_path):
    out = tmp_path / "slow.exr"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "envstudio", "prefilter", "--env", SUNRISE, "--exponent", "10",
         "--algo", "brute", "--param", "cube", "--size", "256", "-o", str(out)],
        stderr=subprocess.PIPE, env=env,
    )  # fmt: skip
    time.sleep(2.5)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert b"interrupted" in err
    assert list(tmp_path.iterdir()) == []


def test_bench_prefilter_table_json_and_plot(tmp_path):
    radiance = smooth_map(32, seed=5)
    report = run_prefilter_bench(radiance, 16, [10, 500], sweep=(8, 16), repeats=2, threads=2)
    rows = {row["exponent"]: row for row in report["rows"]}
    assert set(rows) == {10.0, 500.0}
    assert rows[500.0]["paper"]["speedup"] == 14.1
    for row in rows.values():
        assert row["max_difference_over_mean"] < 0.01
        assert row["speedup"] == pytest.approx(row["brute_s"] / row["hierarchical_s"])
        assert row["brute_s"] == min(row["brute_runs_s"]) and len(row["brute_runs_s"]) == 2
    assert [p["face"] for p in report["sweep"]] == [8, 16]
    assert all(isinstance(v, float) for v in report["sweep_slopes"].values())  # timing: no bound
    json.dumps(report)
    plot = write_scaling_plot(report, tmp_path / "scaling.png")
    spec = oiio.ImageInput.open(str(plot)).spec()
    assert spec.width > 100 and spec.height > 100


def test_bench_prefilter_command(tmp_path, capsys):
    status = main(["bench", "--prefilter", "--env", SUNRISE, "--size", "8x16", "--exponents", "10"])
    assert status == 0
    table = capsys.readouterr().out
    assert "paraboloid 2x8x8" in table and "413" in table
    status = main(["bench", "--prefilter", "--size", "100x200"])
    assert status == 2


def test_paraboloid_picture_layout():
    """The paraboloid picture is front | back, upright: the front centre looks down +Z."""
    maps = np.zeros((2, 4, 4, 3))
    maps[0, 0, 0] = 1.0  # front face, row 0 (t = −1: bottom of the picture)
    picture = target_picture("paraboloid", maps)
    assert picture[3, 0, 0] == 1.0 and picture.shape == (4, 8, 3)


# --- the mip chain for engines ---------------------------------------------------------------


def test_gloss_exponents_follow_the_cmft_convention():
    exponents = gloss_exponents(8, 10.0, 1.0)
    assert exponents[0] == 2.0**11 and exponents[-1] == 2.0
    assert np.allclose(np.diff(np.log2(exponents)), -10.0 / 7)


def test_chain_level_zero_matches_the_brute_force():
    image = smooth_map(32, seed=4)
    chain = prefiltered_chain(image, 8, 4, 4.0, 1.0)
    assert [level.faces.shape[1] for level in chain] == [8, 4, 2, 1]
    assert chain[0].exponent == 32.0
    brute = brute_force.prefilter(image, cubemap.texel_directions(8), kernels.phong(32.0))
    assert relative_max_difference(chain[0].faces, brute) < 0.005


def read_dds_cube(path: Path) -> list[np.ndarray]:
    """A reader written from Microsoft's DDS layout (OpenImageIO 3.2 and Pillow 13 refuse
    DXGI format 10): header fields, then per face every level's RGBA halves."""
    data = path.read_bytes()
    assert data[:4] == b"DDS "
    size, _, height, width, _, _, mips = struct.unpack_from("<7I", data, 4)
    assert size == 124 and height == width
    assert data[84:88] == b"DX10"
    caps, caps2 = struct.unpack_from("<2I", data, 108)
    assert caps & 0x400000  # mip-mapped
    assert caps2 & 0x200 and caps2 & 0xFC00 == 0xFC00  # cube map, all faces
    dxgi, dimension, misc, array_size, _ = struct.unpack_from("<5I", data, 128)
    assert (dxgi, dimension, misc, array_size) == (10, 3, 4, 1)
    texels = np.frombuffer(data, dtype="<f2", offset=148).astype(np.float32)
    levels = [np.empty((6, max(1, width >> k), max(1, width >> k), 4)) for k in range(mips)]
    offset = 0
    for face in range(6):
        for level in levels:
            count = level[face].size
            level[face] = texels[offset : offset + count].reshape(level.shape[1:])
            offset += count
    assert offset == len(texels)
    return levels


def test_dds_round_trip(tmp_path):
    rng = np.random.default_rng(9)
    levels = [rng.uniform(0, 50, size=(6, 8 >> k, 8 >> k, 3)) for k in range(4)]
    path = write_dds_cube(tmp_path / "cube.dds", levels)
    back = read_dds_cube(path)
    for wrote, read in zip(levels, back, strict=True):
        assert np.allclose(read[..., :3], wrote, rtol=1e-3)
        assert np.all(read[..., 3] == 1.0)


def test_dds_rgba8_cube_read_back_by_openimageio(tmp_path):
    """The DDS container (header, DX10 block, cube flags, face order, mip chain) through an
    independent reader: OpenImageIO reads the RGBA8 file the writer makes with the layout of
    the RGBA16F one, texel by texel, every face and level.

    OpenImageIO 3.2's DDS reader gives cube mip level m the size of level m - 1 (its size
    loop starts at 1), so a face's tile holds level m's texels first, then runs on into the
    following data; the comparison takes the first n_m² texels of each face, and the copy
    OpenImageIO reads is padded so that the last face's longer read does not hit the end.
    """
    rng = np.random.default_rng(5)
    levels = [rng.uniform(-0.1, 1.1, size=(6, 8 >> k, 8 >> k, 3)) for k in range(4)]
    path = write_dds_cube(tmp_path / "cube.dds", levels, pixel_format="rgba8")
    padded = tmp_path / "padded.dds"
    padded.write_bytes(path.read_bytes() + bytes(4 * 8 * 8))
    inp = oiio.ImageInput.open(str(padded))
    assert inp is not None, oiio.geterror()
    try:
        assert inp.spec().get_string_attribute("textureformat") == "CubeFace Environment"
        assert inp.spec().get_string_attribute("dds:CubeMapSides") == "+x -x +y -y +z -z"
        assert not inp.seek_subimage(0, len(levels))
        for m, level in enumerate(levels):
            assert inp.seek_subimage(0, m)
            spec = inp.spec()
            assert spec.nchannels == 4 and spec.format == "uint8"
            want = np.rint(np.clip(level, 0, 1) * 255)
            for face in range(6):
                tile = inp.read_tile(0, face * spec.tile_height, 0, "uint8")
                assert tile is not None, inp.geterror()
                texels = np.asarray(tile).reshape(-1, 4)[: want[face].size // 3]
                assert np.array_equal(texels[:, :3], want[face].reshape(-1, 3)), (m, face)
                assert np.all(texels[:, 3] == 255)
    finally:
        inp.close()
    # The RGBA16F file: the same bytes but for the DXGI format, the pitch and the texels.
    half = write_dds_cube(tmp_path / "half.dds", levels).read_bytes()
    byte = path.read_bytes()
    assert (
        half[:20] == byte[:20] and half[24:128] == byte[24:128] and half[132:148] == byte[132:148]
    )
    assert (
        struct.unpack_from("<I", half, 128)[0] == 10
        and struct.unpack_from("<I", byte, 128)[0] == 28
    )


def test_openimageio_reads_no_float_dds(tmp_path):
    """Why the RGBA16F round trip uses the test's own reader (io/dds.py's docstring)."""
    path = write_dds_cube(tmp_path / "cube.dds", [np.ones((6, 4, 4, 3)), np.ones((6, 2, 2, 3))])
    assert oiio.ImageInput.open(str(path)) is None
    assert "Unsupported DXGI format: 10" in oiio.geterror()
    legacy = bytearray(path.read_bytes())
    legacy[84:88] = struct.pack("<I", 113)  # D3DFMT_A16B16G16R16F as the FourCC, no DX10 block
    (tmp_path / "legacy.dds").write_bytes(bytes(legacy[:128] + legacy[148:]))
    assert oiio.ImageInput.open(str(tmp_path / "legacy.dds")) is None
    assert "Unsupported compression type: 113" in oiio.geterror()


def test_chain_command_writes_dds_exr_and_sh(tmp_path, capsys):
    argv = ["prefilter", "--chain", "--env", SUNRISE, "--param", "cube", "--size", "8",
            "--levels", "3", "--source-height", "32", "--check"]  # fmt: skip
    assert main([*argv, "-o", str(tmp_path / "chain.dds")]) == 0
    out = capsys.readouterr().out
    assert "level 2: 2² N = 2" in out and "vs brute force" in out
    levels = read_dds_cube(tmp_path / "chain.dds")
    assert [level.shape[1] for level in levels] == [8, 4, 2]
    sh = json.loads((tmp_path / "chain.sh.json").read_text())
    assert np.shape(sh["coefficients"]) == (9, 3)
    assert main([*argv, "-o", str(tmp_path / "chain.exr")]) == 0
    assert read_image(tmp_path / "chain_mip1.exr").shape == (12, 16, 3)
    assert np.allclose(cubemap.cross_to_faces(read_image(tmp_path / "chain_mip0.exr")),
                       levels[0][..., :3], rtol=2e-3, atol=1e-4)  # fmt: skip


@pytest.mark.parametrize(
    ("extra", "fragments"),
    [
        (["--param", "paraboloid"], ["--chain", "--param cube"]),
        (["--param", "cube", "--size", "8", "--levels", "5"], ["--levels 5", "1..4"]),
        (["--param", "cube", "--size", "12"], ["--size 12", "power of two"]),
        (["--param", "cube", "--gloss-scale", "0"], ["--gloss-scale 0"]),
        (["--param", "cube", "--algo", "spectral", "--device", "gpu"], ["--algo spectral", "CPU"]),
        (["--param", "cube", "--size", "16384", "--algo", "spectral"], ["--size 16384", "MiB"]),
    ],
)
def test_chain_bad_input(tmp_path, capsys, extra, fragments):
    argv = ["prefilter", "--chain", "--env", SUNRISE, *extra, "-o", str(tmp_path / "c.dds")]
    assert_one_line_error(main(argv), capsys.readouterr().err, *fragments)
    assert not list(tmp_path.iterdir())


# --- the spectral chain (prefilter.spectral) ---------------------------------------------------


def test_spectral_chain_matches_the_brute_force_at_every_level():
    image = smooth_map(64, seed=5)
    chain = spectral.spectral_chain(image, 16, 5, 6.0, 1.0)
    assert [level.faces.shape[1] for level in chain] == [16, 8, 4, 2, 1]
    for level in chain:
        n = level.faces.shape[1]
        brute = brute_force.prefilter(
            image, cubemap.texel_directions(n), kernels.phong(level.exponent)
        )
        assert relative_max_difference(level.faces, brute) < SPECTRAL_SMOOTH_TOLERANCE, (
            level.exponent
        )


#: Measured: at most 1.2e-4 of the mean on this map (N = 128 … 2); the README's studio
#: chain is under 0.04 % rms / 0.4 % max at every level.
SPECTRAL_SMOOTH_TOLERANCE = 3e-4


@pytest.mark.parametrize(
    ("height", "exponent"), [(128, 100.0), (128, 20.0), (128, 3.0), (64, 300.0), (32, 500.0)]
)
def test_spectral_single_bright_texel_gives_the_kernel(height, exponent):
    """A point light near the pole: the filtered cube is the lobe placed at that texel's
    direction, so the phase, the row weights and the pole padding all have to be right. The
    last two lobes are narrower than the source's texels (the grid splits each source row,
    the spectrum repeats beyond the source's columns)."""
    image = np.zeros((height, 2 * height, 3), np.float32)
    image[5, 37] = (1.0, 2.0, 3.0)
    level = spectral.plan(height, 2 * height, exponent)
    got = spectral.phong_spectral(spectral.source_spectrum(image, level.frequencies), level, 16)
    brute = brute_force.prefilter(image, cubemap.texel_directions(16), kernels.phong(exponent))
    assert np.abs(got - brute).max() < 1e-3 * brute.max()  # measured 1.6e-5 … 3.6e-4


def test_spectral_chain_keeps_a_constant_map_constant():
    image = np.full((128, 256, 3), 0.5, np.float32)
    for level in spectral.spectral_chain(image, 16, 4, 6.0, 1.0):
        n = level.faces.shape[1]
        brute = brute_force.prefilter(
            image, cubemap.texel_directions(n), kernels.phong(level.exponent)
        )
        assert np.abs(level.faces - 0.5).max() < 1e-3
        assert np.abs(level.faces - brute).max() < 1e-4


def test_spectral_chain_is_continuous_across_face_edges():
    """Each texel on a face edge against its neighbour across the edge: no larger step than
    between neighbours inside a face (the method reads directions, not faces)."""
    image = brute_force.downsample_latlong(read_environment(SUNRISE), 64)
    faces = spectral.spectral_chain(image, 16, 1, 6.0, 1.0)[0].faces
    n = faces.shape[1]
    inside = max(np.abs(np.diff(faces, axis=1)).max(), np.abs(np.diff(faces, axis=2)).max())
    d = cubemap.texel_directions(n)
    across = 0.0
    for f in range(6):
        for edge in (d[f, 0], d[f, -1], d[f, :, 0], d[f, :, -1]):
            for texel in edge:
                step = texel - d[f, n // 2, n // 2] * np.dot(texel, d[f, n // 2, n // 2])
                face, uv = cubemap.direction_to_uv(texel + 1.0 / n * step / np.linalg.norm(step))
                if face == f:
                    continue
                j, i = np.minimum((uv * n).astype(int), n - 1)
                mine = cubemap.direction_to_uv(texel)[1]
                jm, im = np.minimum((mine * n).astype(int), n - 1)
                across = max(across, float(np.abs(faces[face, i, j] - faces[f, im, jm]).max()))
    assert 0 < across <= 1.5 * inside


def test_spectral_row_prefilter_is_the_cubic_spline_prefilter():
    x = np.random.default_rng(3).random((60, 7)).astype(np.float32)
    ours = spectral._prefilter_rows(x)
    scipy_ = ndimage.spline_filter1d(x, 3, axis=0, mode="mirror")
    assert np.abs(ours - scipy_)[8:-8].max() < 1e-5


def test_spectral_chain_command(tmp_path, capsys):
    argv = ["prefilter", "--chain", "--env", SUNRISE, "--param", "cube", "--size", "8",
            "--levels", "3", "--source-height", "32", "--algo", "spectral", "--check"]  # fmt: skip
    assert main([*argv, "-o", str(tmp_path / "chain.dds")]) == 0
    out = capsys.readouterr().out
    assert "CPU (spectral)" in out and "level 2: 2² N = 2" in out
    assert [level.shape[1] for level in read_dds_cube(tmp_path / "chain.dds")] == [8, 4, 2]


def test_spectral_needs_the_chain(tmp_path, capsys):
    argv = ["prefilter", "--env", SUNRISE, "--kernel", "phong", "--exponent", "10",
            "--algo", "spectral", "-o", str(tmp_path / "m.exr")]  # fmt: skip
    assert_one_line_error(main(argv), capsys.readouterr().err, "--algo spectral", "--chain")
    assert not list(tmp_path.iterdir())


def test_chain_bench_reports_the_spectral_chain():
    from envstudio.prefilter.bench import format_chain_report, run_chain_bench

    report = run_chain_bench(smooth_map(64, seed=6), sizes=(16,), repeats=1, gpu=False)
    (entry,) = report["spectral"]["sizes"]
    assert entry["size"] == 16 and entry["cold_seconds"] > 0 and len(entry["levels"]) == 8
    assert all(level["rms"] < 1e-3 for level in entry["levels"])  # N = 2048: measured 2.2e-4
    text = format_chain_report(report)
    assert "CPU spectral" in text and "level 7: 1² N = 2" in text and report["gpu"] is None
