"""Bad input: one line naming the file or value and what was expected, exit status 2."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from envstudio.cli import main
from envstudio.io.images import read_image, write_image
from envstudio.methods.pem.method import shipped_bake
from envstudio.resources import asset_root

BUNNY = str(asset_root() / "mesh" / "bunny.ply")
STUDIO = str(asset_root() / "hdr" / "studio.exr")


def run_cli(capsys, *argv: str) -> tuple[int, str]:
    status = main(list(argv))
    err = capsys.readouterr().err
    return status, err


def assert_one_line_error(status: int, err: str, *fragments: str) -> None:
    assert status == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


@pytest.fixture
def bad_files(tmp_path: Path) -> dict[str, Path]:
    files = {}
    files["missing"] = tmp_path / "missing.exr"
    files["text"] = tmp_path / "notes.exr"
    files["text"].write_text("this is not an image\n")
    files["truncated"] = tmp_path / "truncated.exr"
    files["truncated"].write_bytes(Path(STUDIO).read_bytes()[:5000])
    files["square"] = tmp_path / "square.exr"
    write_image(files["square"], np.ones((16, 16, 3), np.float32))
    nan_map = np.ones((16, 32, 3), np.float32)
    nan_map[3, 5, 0] = np.nan
    nan_map[4, 6, 0] = np.inf
    files["nan"] = tmp_path / "nan.exr"
    out = oiio.ImageOutput.create(str(files["nan"]))
    out.open(str(files["nan"]), oiio.ImageSpec(32, 16, 3, "float"))
    out.write_image(nan_map)
    out.close()
    files["nofaces"] = tmp_path / "points.obj"
    files["nofaces"].write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    return files


@pytest.mark.parametrize(
    ("key", "fragments"),
    [
        ("missing", ["missing.exr", "no such file"]),
        ("text", ["notes.exr", "not a readable image"]),
        ("truncated", ["truncated.exr", "corrupt"]),
        ("square", ["square.exr", "16x16", "width = 2 x height"]),
        ("nan", ["nan.exr", "2 pixels are NaN or Inf", "x=5, y=3"]),
    ],
)
def test_bad_environment_files(capsys, tmp_path, bad_files, key, fragments):
    status, err = run_cli(
        capsys,
        "render",
        "--env",
        str(bad_files[key]),
        "--mesh",
        BUNNY,
        "-o",
        str(tmp_path / "out.png"),
    )
    assert_one_line_error(status, err, *fragments)
    assert not (tmp_path / "out.png").exists()


def test_mesh_without_faces(capsys, tmp_path, bad_files):
    status, err = run_cli(
        capsys, "render", "--mesh", str(bad_files["nofaces"]), "-o", str(tmp_path / "out.png")
    )
    assert_one_line_error(status, err, "points.obj", "no faces")


@pytest.mark.parametrize(
    ("argv", "fragments"),
    [
        (["render", "--method", "phong", "-o", "OUT"], ["unknown method 'phong'", "mirror"]),
        (
            ["render", "--param", "lod_bias=2", "-o", "OUT"],
            ["unknown parameter 'lod_bias'", "fresnel"],
        ),
        (["render", "--param", "fresnel=1.5", "-o", "OUT"], ["fresnel=1.5", "[0, 1]"]),
        (["render", "--param", "tonemap=filmic", "-o", "OUT"], ["tonemap=filmic", "aces"]),
        (["render", "--size", "big", "-o", "OUT"], ["--size 'big'", "WIDTHxHEIGHT"]),
        (["render", "--camera", "1,2", "-o", "OUT"], ["--camera '1,2'"]),
        (["render", "-o", "MISSING/out.png"], ["MISSING", "does not exist"]),
        (["render", "-o", "OUT.txt"], ["OUT.txt", ".png or .exr"]),
        (["render", "--scene", "nowhere", "-o", "OUT"], ["nowhere", "studio"]),
        (["bench", "--methods", "mirror,nope"], ["unknown method 'nope'"]),
        (["bench", "--converge", "--methods", "kautz"], ["--converge", "only 'reference'"]),
        (["bench", "--converge", "--time-limit", "-1"], ["--time-limit -1", "positive"]),
        (["bench", "--resume"], ["--resume", "only with --converge"]),
        (["render", "--bogus", "-o", "OUT"], ["unrecognized arguments: --bogus"]),
        (["nowhere.exr"], ["nowhere.exr", "no such file"]),  # envstudio FILE = view FILE
        (["render", "--method", "pem", "--param", "pem=nowhere.pem", "-o", "OUT"], ["nowhere"]),
        (
            ["render", "--method", "pem", "--scene", "studio", "--param", "pem=ROOM", "-o", "OUT"],
            ["a bake of scene 'room', expected one of 'studio'"],
        ),
        (["bake", "pem", "--scene", "room", "--elevations", "0", "-o", "OUT"], ["--elevations 0"]),
        (["bake", "pem", "--scene", "room", "--tie", "-1", "-o", "OUT"], ["--tie -1", "[0, 10]"]),
        (["render", "--camera", "nan,0,3", "-o", "OUT"], ["--camera 'nan,0,3'", "finite"]),
        (["render", "--camera", "0,0,inf", "-o", "OUT"], ["--camera '0,0,inf'", "distance"]),
        (["render", "--camera", "0,nan,3", "-o", "OUT"], ["--camera '0,nan,3'", "[-90, 90]"]),
        (["bench", "--methods", ""], ["--methods ''", "method names"]),
        (["bench", "--methods", " , "], ["--methods ' , '", "method names"]),
        (["bench", "--triangles", "0"], ["--triangles 0", "expected 1.."]),
        (["bench", "--triangles", "-5"], ["--triangles -5", "expected 1.."]),
        (["bench", "--triangles", "1000000000"], ["--triangles 1000000000", "20,000,000"]),
        (
            ["render", "--method", "hwconv", "--param", "border=65536", "-o", "OUT"],
            ["border=65536", "GL_MAX_TEXTURE_SIZE"],
        ),
        (["bench", "--methods", "mirror", "--json", "OUT.txt"], ["OUT.txt", ".json file"]),
        (["bake", "rsibr", "--env", STUDIO, "-o", "OUT.txt"], ["OUT.txt", ".rsibr file"]),
        (["bake", "pem", "--scene", "room", "-o", "OUT.txt"], ["OUT.txt", ".pem file"]),
        (["sh", "--env", STUDIO, "--max-env-width", "4"], ["--max-env-width 4", "at least 8"]),
        (["compare", "--methods", "mirror", "--ssaa", "0", "--out", "OUT.d"], ["--ssaa 0", "1..8"]),
        (["compare", "--methods", "mirror", "--ssaa", "2.5", "--out", "OUT.d"], ["--ssaa", "2.5"]),
        (
            ["render", "--method", "splitsum", "--param", "roughness=0", "-o", "OUT"],
            ["roughness=0", "[1e-06, 1]"],
        ),
        (
            ["render", "--method", "splitsum", "--param", "roughness=1.5", "-o", "OUT"],
            ["roughness=1.5", "[1e-06, 1]"],
        ),
    ],
)
def test_usage_errors(capsys, tmp_path, argv, fragments):
    """One line, exit 2, and nothing written: an existing output is left as it was."""
    kept = tmp_path / "out.png"
    kept.write_bytes(b"an earlier result")
    argv = [a.replace("OUT", str(kept)) if a == "OUT" else a for a in argv]
    argv = [str(tmp_path / a) if a.startswith(("MISSING", "OUT.")) else a for a in argv]
    argv = [a.replace("ROOM", str(shipped_bake("room"))) for a in argv]
    status, err = run_cli(capsys, *argv)
    assert_one_line_error(status, err, *fragments)
    assert kept.read_bytes() == b"an earlier result"
    assert [p.name for p in tmp_path.iterdir() if p.name != "cache"] == ["out.png"]


def test_bad_scene_file(capsys, tmp_path):
    scene = tmp_path / "broken.toml"
    scene.write_text('[environment]\nfile = "hdr/studio.exr"\n[[object]]\nprimitive = "torus"\n')
    status, err = run_cli(capsys, "render", "--scene", str(scene), "-o", str(tmp_path / "o.png"))
    assert_one_line_error(status, err, "broken.toml", "object[0]", "primitive")
    scene.write_text("this is = = not toml")
    status, err = run_cli(capsys, "render", "--scene", str(scene), "-o", str(tmp_path / "o.png"))
    assert_one_line_error(status, err, "broken.toml", "not a valid TOML")


def test_no_egl_is_one_line_in_a_real_process(tmp_path):
    env = dict(
        os.environ,
        __EGL_VENDOR_LIBRARY_FILENAMES=str(tmp_path / "none.json"),
        EGL_PLATFORM="surfaceless",
        LIBGL_ALWAYS_SOFTWARE="1",
    )
    env["__EGL_VENDOR_LIBRARY_DIRS"] = str(tmp_path)
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "envstudio",
            "render",
            "--size",
            "32x32",
            "-o",
            str(tmp_path / "x.png"),
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert result.returncode == 2, result.stderr
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert "EGL" in result.stderr and "libegl" in result.stderr


@pytest.mark.parametrize("value", ["0", "-3", "abc", "nan", "inf", "1e9"])
def test_a_bad_time_limit_is_one_line_and_writes_nothing(capsys, tmp_path, value):
    out = tmp_path / "cmp"
    status, err = run_cli(
        capsys, "compare", "--methods", "mirror", "--time-limit", value, "--out", str(out)
    )
    assert_one_line_error(status, err, f"--time-limit {value}", "positive number of seconds")
    assert not out.exists()
    png = tmp_path / "ref.png"
    argv = ["render", "--method", "reference", "--time-limit", value, "-o", str(png)]
    status, err = run_cli(capsys, *argv)
    assert_one_line_error(status, err, f"--time-limit {value}", "positive number of seconds")
    assert not png.exists()


def test_a_time_limit_for_a_one_frame_method_or_out_of_range_is_one_line(capsys, tmp_path):
    png = tmp_path / "out.png"
    status, err = run_cli(
        capsys, "render", "--method", "mirror", "--time-limit", "5", "-o", str(png)
    )
    assert_one_line_error(status, err, "--time-limit", "method mirror", "progressive")
    out = tmp_path / "cmp"
    argv = ["compare", "--methods", "mirror", "--param", "time_limit=-1", "--out", str(out)]
    status, err = run_cli(capsys, *argv)
    assert_one_line_error(status, err, "time_limit=-1", "[0, 1e+06]")
    assert not png.exists() and not out.exists()


@pytest.mark.parametrize(
    ("material", "fragments"),
    [
        ("sharpness = 1.5", ["object[0].material.sharpness = 1.5", "[0, 1)"]),
        ('tangent_field = "spiral"', ["object[0].material.tangent_field = 'spiral'", "uv"]),
        ('tangent_axis = "w"', ["object[0].material.tangent_axis = 'w'", "x, y, z"]),
    ],
)
def test_bad_banks_material_in_a_scene_file(capsys, tmp_path, material, fragments):
    scene = tmp_path / "brushed.toml"
    scene.write_text(
        '[environment]\nfile = "hdr/studio.exr"\n[[object]]\nprimitive = "sphere"\n'
        f"[object.material]\n{material}\n"
    )
    status, err = run_cli(capsys, "render", "--scene", str(scene), "-o", str(tmp_path / "o.png"))
    assert_one_line_error(status, err, "brushed.toml", *fragments)


def test_an_8_bit_image_is_not_an_environment(capsys, tmp_path):
    path = tmp_path / "photo.png"
    write_image(path, np.full((16, 32, 3), 0.5, np.float32))
    status, err = run_cli(capsys, "render", "--env", str(path), "-o", str(tmp_path / "o.png"))
    assert_one_line_error(status, err, "photo.png", "linear HDR", "display values")


def test_a_map_too_large_for_the_memory_is_refused_from_its_header(capsys, tmp_path, monkeypatch):
    """The estimate comes from the header; --max-env-width box-filters the map as it is read."""
    path = tmp_path / "big.exr"
    radiance = np.random.default_rng(1).random((256, 512, 3)).astype(np.float32)
    write_image(path, radiance)
    monkeypatch.setenv("ENVSTUDIO_MEMORY_MB", "10")
    status, err = run_cli(capsys, "sh", "--env", str(path))
    assert_one_line_error(status, err, "512x256", "10 MB are available", "--max-env-width 256")
    assert main(["sh", "--env", str(path), "--max-env-width", "128", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["source"] == "128x64 lat-long"
    # L0 = ∫ L Y0: the box filter keeps the map's mean radiance (the solid angles change little)
    assert report["coefficients"][0][0] == pytest.approx(
        float(np.mean(read_image(path)[..., 0])) * 2 * np.sqrt(np.pi), rel=0.01
    )


@pytest.mark.parametrize("option", ["--scene", "--env", "--mesh"])
def test_a_file_name_the_system_refuses_is_one_line(capsys, tmp_path, option):
    """An operating-system error on a named file (a name longer than the file system takes)
    is the file and the reason on one line, exit 2: the class, not one call site."""
    name = "x" * 300 + {"--scene": "", "--env": ".exr", "--mesh": ".obj"}[option]
    status, err = run_cli(
        capsys,
        "render",
        "--method",
        "mirror",
        option,
        name,
        "--size",
        "8x8",
        "-o",
        str(tmp_path / "o.png"),
    )
    assert_one_line_error(status, err, name, "too long")
    assert not (tmp_path / "o.png").exists()
