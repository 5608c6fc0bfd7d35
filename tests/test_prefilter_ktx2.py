"""Chains other engines load (issue 30): KTX2, EXT_lights_image_based, the GGX CPU chain.

The KTX2 file is checked field by field against the constants of the KTX 2.0 specification
(ktxspec.adoc) and the Khronos Data Format descriptor libktx writes for
VK_FORMAT_R16G16B16A16_SFLOAT, and texel by texel through two readers nobody here wrote:
ktx-parse (npm, the parser three.js vendors) under Node, and three.js's own KTX2Loader in
headless Chromium. Both come from the npm registry into .node/ (run.sh installs them).
"""

from __future__ import annotations

import json
import shutil
import struct
import subprocess
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from envstudio.cli import main
from envstudio.core import cubemap, sh
from envstudio.io.gltf_ibl import decode_rgbd
from envstudio.io.images import write_image
from envstudio.io.ktx2 import write_ktx2_cube
from envstudio.prefilter import brute_force, kernels, roughness, spectral

ROOT = Path(__file__).resolve().parents[1]
NODE_MODULES = ROOT / ".node" / "node_modules"
RUN_SH = "run ./run.sh once: it installs three and ktx-parse from npm into .node/"


def random_chain(size: int = 8, levels: int = 4) -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    return [
        (rng.random((6, size >> k, size >> k, 3)) * 8.0).astype(np.float32) for k in range(levels)
    ]


def expected_halves(level: np.ndarray) -> np.ndarray:
    """The file's texels of a level as uint16: RGBA half floats, A = 1, faces in order."""
    rgba = np.concatenate([level, np.ones((*level.shape[:3], 1), np.float32)], axis=-1)
    return rgba.astype("<f2").view("<u2").ravel()


def assert_one_line_error(status: int, err: str, *fragments: str) -> None:
    assert status == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("envstudio: error:"), err
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])


def test_ktx2_header_index_and_dfd_are_the_spec_s(tmp_path):
    levels = random_chain()
    data = write_ktx2_cube(tmp_path / "c.ktx2", levels, {"envstudio.kernel": "ggx"}).read_bytes()
    # ktxspec §4.1: «KTX 20»\r\n\x1A\n
    assert data[:12] == bytes(
        [0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A]
    )
    header = struct.unpack_from("<9I", data, 12)
    # vkFormat R16G16B16A16_SFLOAT = 97, typeSize 2, 8 × 8, depth 0, not an array, a cube,
    # four levels, no supercompression
    assert header == (97, 2, 8, 8, 0, 0, 6, 4, 0)
    dfd_offset, dfd_length, kvd_offset, kvd_length, sgd_offset, sgd_length = struct.unpack_from(
        "<4I2Q", data, 48
    )
    assert dfd_offset == 80 + 4 * 24 and (sgd_offset, sgd_length) == (0, 0)
    # dfdTotalSize = dfdByteLength = kvdByteOffset − dfdByteOffset = 4 + 24 + 4 × 16
    assert struct.unpack_from("<I", data, dfd_offset)[0] == dfd_length == 92
    assert kvd_offset - dfd_offset == 92
    words = struct.unpack_from("<6I", data, dfd_offset + 4)
    assert words[0] == 0  # vendorId KHRONOS, descriptorType BASICFORMAT
    assert words[1] == 2 | (88 << 16)  # versionNumber 2 (KDF 1.3), descriptorBlockSize 88
    assert words[2] == 1 | 1 << 8 | 1 << 16  # RGBSDA, BT709, LINEAR, ALPHA_STRAIGHT
    assert words[3] == 0 and words[4] == 8 and words[5] == 0  # 1×1×1×1 block, 8 bytes
    for i, channel in enumerate((0, 1, 2, 15)):
        sample = struct.unpack_from("<HBB4BII", data, dfd_offset + 28 + 16 * i)
        # bitOffset 16 i, bitLength 15, FLOAT | SIGNED, position 0, −1.0f … 1.0f
        assert sample == (16 * i, 15, 0xC0 | channel, 0, 0, 0, 0, 0xBF800000, 0x3F800000)
    # key/value data: sorted by key, NUL-terminated, each pair padded to 4 bytes
    pairs, at = {}, kvd_offset
    while at < kvd_offset + kvd_length:
        (length,) = struct.unpack_from("<I", data, at)
        key, _, value = data[at + 4 : at + 4 + length].partition(b"\0")
        pairs[key.decode()] = value.rstrip(b"\0").decode()
        at += 4 + length + (-length % 4)
    assert at == kvd_offset + kvd_length and list(pairs) == sorted(pairs)
    assert pairs["KTXorientation"] == "rd" and pairs["envstudio.kernel"] == "ggx"
    # level index: level 0 first; data smallest level first, 8-byte aligned, to the end
    index = [struct.unpack_from("<3Q", data, 80 + 24 * k) for k in range(4)]
    for k, (offset, length, raw) in enumerate(index):
        assert length == raw == 6 * (8 >> k) ** 2 * 8 and offset % 8 == 0
        assert data[offset : offset + length] == expected_halves(levels[k]).tobytes()
    offsets = [entry[0] for entry in index]
    assert offsets == sorted(offsets, reverse=True) and offsets[-1] >= kvd_offset + kvd_length
    assert offsets[0] + index[0][1] == len(data)


def node_modules() -> Path:
    assert shutil.which("node"), f"no Node.js on this machine: the npm readers cannot run; {RUN_SH}"
    assert (NODE_MODULES / "three").is_dir() and (NODE_MODULES / "ktx-parse").is_dir(), RUN_SH
    return NODE_MODULES


def test_ktx_parse_reads_every_texel(tmp_path):
    modules = node_modules()
    levels = random_chain()
    path = write_ktx2_cube(tmp_path / "c.ktx2", levels, {"envstudio.roughness": "0 0.11 0.44 1"})
    script = tmp_path / "read.mjs"
    script.write_text(
        f"import {{ read }} from '{(modules / 'ktx-parse/dist/index.mjs').as_uri()}';\n"
        "import fs from 'fs';\n"
        f"const c = read(new Uint8Array(fs.readFileSync('{path}')));\n"
        "const text = (v) => typeof v === 'string' ? v : Buffer.from(v).toString();\n"
        "console.log(JSON.stringify({vkFormat: c.vkFormat, faceCount: c.faceCount,\n"
        "  width: c.pixelWidth, transfer: c.dataFormatDescriptor[0].transferFunction,\n"
        "  keys: Object.fromEntries(Object.entries(c.keyValue).map(([k, v]) => [k, text(v)])),\n"
        "  levels: c.levels.map((l) =>\n"
        "    Array.from(new Uint16Array(l.levelData.slice().buffer)))}));\n"
    )
    result = subprocess.run(["node", str(script)], capture_output=True, text=True, timeout=60)
    got = json.loads(result.stdout)
    assert (got["vkFormat"], got["faceCount"], got["width"], got["transfer"]) == (97, 6, 8, 1)
    assert got["keys"]["envstudio.roughness"].rstrip("\0") == "0 0.11 0.44 1"
    assert got["keys"]["KTXorientation"] == "rd"
    for k, level in enumerate(levels):
        np.testing.assert_array_equal(got["levels"][k], expected_halves(level))


def test_three_ktx2loader_in_chromium_reads_every_texel(tmp_path):
    """three.js r187's KTX2Loader gives an uncompressed cube as a DataTexture (not a cube
    texture: it builds cubes only for compressed formats) whose mipmaps hold each level's
    six faces in order; its colour space comes from the DFD (BT709, linear)."""
    modules = node_modules()
    browser = shutil.which("chromium")
    assert browser, "chromium (Debian package) is needed for three.js's KTX2Loader"
    levels = random_chain()
    path = write_ktx2_cube(tmp_path / "c.ktx2", levels)
    imports = {
        "three": (modules / "three/build/three.module.js").as_uri(),
        "three/addons/": (modules / "three/examples/jsm").as_uri() + "/",
    }
    (tmp_path / "index.html").write_text(
        '<!doctype html><html><body><pre id="out">pending</pre>\n'
        f'<script type="importmap">{json.dumps({"imports": imports})}</script>\n'
        '<script type="module">\n'
        "import * as THREE from 'three';\n"
        "import { KTX2Loader } from 'three/addons/loaders/KTX2Loader.js';\n"
        "const out = document.getElementById('out');\n"
        "try {\n"
        "  const loader = new KTX2Loader().detectSupport(new THREE.WebGLRenderer());\n"
        f"  const tex = await loader.loadAsync('{path.as_uri()}');\n"
        "  out.textContent = JSON.stringify({type: tex.type === THREE.HalfFloatType,\n"
        "    format: tex.format === THREE.RGBAFormat, colorSpace: tex.colorSpace,\n"
        "    levels: tex.mipmaps.map((m) => [m.width, Array.from(m.data)])});\n"
        "} catch (e) { out.textContent = 'error: ' + e; }\n"
        "</script></body></html>\n"
    )
    page = subprocess.run(
        [browser, "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", "--allow-file-access-from-files",
         "--virtual-time-budget=10000", "--dump-dom", (tmp_path / "index.html").as_uri()],
        capture_output=True, text=True, timeout=120,
    ).stdout  # fmt: skip
    text = page.split('id="out">')[1].split("</pre>")[0]
    got = json.loads(text.replace("&quot;", '"'))
    assert got["type"] and got["format"] and got["colorSpace"] == "srgb-linear"
    for k, level in enumerate(levels):
        width, texels = got["levels"][k]
        assert width == 8 >> k
        np.testing.assert_array_equal(texels, expected_halves(level))


def test_a_constant_environment_gives_constant_levels_and_light(tmp_path, capsys):
    colour = np.array([0.75, 0.5, 2.0], np.float32)
    env = write_image(tmp_path / "flat.exr", np.broadcast_to(colour, (32, 64, 3)))
    argv = ["prefilter", "--chain", "--kernel", "ggx", "--env", str(env), "--param", "cube",
            "--size", "8", "--levels", "4", "--gltf", "-o", str(tmp_path / "c.ktx2")]  # fmt: skip
    assert main(argv) == 0
    assert "level 3: 1² alpha = 1" in capsys.readouterr().out
    data = (tmp_path / "c.ktx2").read_bytes()
    for k in range(4):
        offset, length, _ = struct.unpack_from("<3Q", data, 80 + 24 * k)
        texels = np.frombuffer(data, "<f2", length // 2, offset).reshape(-1, 4)
        # half floats (5e-4) and the spectral filter's omitted tails and spline (1e-3)
        np.testing.assert_allclose(
            texels[:, :3], np.broadcast_to(colour, (len(texels), 3)), rtol=2e-3
        )
    document = json.loads((tmp_path / "c.gltf").read_text())
    light = document["extensions"]["EXT_lights_image_based"]["lights"][0]
    assert document["scenes"][0]["extensions"]["EXT_lights_image_based"]["light"] == 0
    assert light["specularImageSize"] == 8 and np.shape(light["specularImages"]) == (4, 6)
    assert light["extras"]["envstudio.roughness"] == " ".join(
        f"{a:.9g}" for a in roughness.level_alphas(4)
    )
    # irradiance SH: E(n) = Σ c_i Y_i(n) = π · colour for every normal
    irradiance = (
        np.asarray(light["irradianceCoefficients"]).T
        @ sh.sh9_basis(cubemap.texel_directions(2).reshape(-1, 3)).T
    )
    np.testing.assert_allclose(irradiance.T, np.pi * np.broadcast_to(colour, (24, 3)), rtol=1e-3)
    # the RGBD faces, read by OpenImageIO as the bytes the PNG holds
    for index in np.ravel(light["specularImages"]):
        config = oiio.ImageSpec()
        config.attribute("oiio:UnassociatedAlpha", 1)  # the bytes as stored
        pixels = oiio.ImageBuf(str(tmp_path / document["images"][index]["uri"]), 0, 0, config)
        pixels = pixels.get_pixels(oiio.UINT8)
        assert pixels.shape[2] == 4
        decoded = decode_rgbd(pixels).reshape(-1, 3)
        np.testing.assert_allclose(decoded, np.broadcast_to(colour, decoded.shape), rtol=0.02)


def test_the_ggx_chain_matches_the_brute_force():
    rng = np.random.default_rng(3)
    image = rng.random((32, 64, 3)).astype(np.float32) + 0.5
    image[4, 9] = 40.0  # a small bright light
    chain = spectral.ggx_spectral_chain(image, 8, 4)
    assert [round(level.exponent, 6) for level in chain] == [0.0, 0.111111, 0.444444, 1.0]
    for level in chain[1:]:
        brute = brute_force.prefilter(
            image, cubemap.texel_directions(level.faces.shape[1]), kernels.ggx(level.exponent)
        )
        assert np.abs(level.faces - brute).max() < 2e-3 * brute.mean(), level.exponent


ENV = str(ROOT / "assets" / "hdr" / "sunrise.exr")


@pytest.mark.parametrize(
    ("extra", "fragments"),
    [
        (["--kernel", "ggx", "--pixel-format", "rgba8", "--levels", "3"], ["rgba8", "HDR"]),
        (["--kernel", "ggx", "--levels", "0"], ["--levels 0", "1..4"]),
        (["--kernel", "ggx", "--levels", "5"], ["--levels 5", "1..4"]),
        (
            ["--kernel", "ggx", "--levels", "3", "--algo", "hierarchical", "--device", "cpu"],
            ["--kernel ggx", "spectral"],
        ),
    ],
)
def test_chain_bad_input_for_ggx(tmp_path, capsys, extra, fragments):
    argv = ["prefilter", "--chain", "--env", ENV, "--param", "cube", "--size", "8", *extra,
            "-o", str(tmp_path / "c.dds")]  # fmt: skip
    assert_one_line_error(main(argv), capsys.readouterr().err, *fragments)
    assert not list(tmp_path.iterdir())


def test_ggx_and_pixel_format_need_a_chain_and_a_dds(tmp_path, capsys):
    argv = ["prefilter", "--env", ENV, "--kernel", "ggx", "-o", str(tmp_path / "m.exr")]
    assert_one_line_error(main(argv), capsys.readouterr().err, "--kernel ggx", "--chain")
    argv = ["prefilter", "--chain", "--env", ENV, "--param", "cube", "--size", "8", "--levels",
            "3", "--pixel-format", "rgba8", "-o", str(tmp_path / "c.ktx2")]  # fmt: skip
    assert_one_line_error(main(argv), capsys.readouterr().err, "--pixel-format", ".dds")
