"""``envstudio envmap``: the GPU conversions written to EXR match the NumPy resampling."""

import numpy as np
import pytest

from envstudio.cli import main
from envstudio.core import cubemap, resample
from envstudio.io.images import read_environment, read_image, write_image


@pytest.fixture
def smooth_env(tmp_path):
    from envstudio.core import latlong

    d = latlong.texel_directions(32)
    img = np.stack([1 + d[..., 0], 1 + d[..., 1] ** 2, 1.5 - d[..., 2]], -1).astype(np.float32)
    path = tmp_path / "smooth.exr"
    write_image(path, img)
    return path, read_environment(path)


def test_cube_cross_matches_numpy(tmp_path, smooth_env, capsys):
    path, img = smooth_env
    out = tmp_path / "cube.exr"
    assert main(["envmap", "--env", str(path), "--to", "cube", "--size", "16", "-o", str(out)]) == 0
    faces = cubemap.cross_to_faces(read_image(out)[..., :3])
    expected = resample.latlong_to_cube(img, 16)
    np.testing.assert_allclose(faces, expected, atol=2e-2, rtol=2e-2)


@pytest.mark.parametrize(
    ("target", "shape"),
    [("latlong", (16, 32, 3)), ("paraboloid", (16, 32, 3)), ("spheremap", (16, 16, 3))],
)
def test_every_representation_is_written(tmp_path, smooth_env, target, shape):
    path, _ = smooth_env
    out = tmp_path / f"{target}.exr"
    argv = ["envmap", "--env", str(path), "--to", target, "--size", "16", "-o", str(out)]
    assert main(argv) == 0
    pixels = read_image(out)[..., :3]
    assert pixels.shape == shape
    assert pixels.max() > 1.0 and np.isfinite(pixels).all()


def test_bad_size_is_one_line(tmp_path, smooth_env, capsys):
    path, _ = smooth_env
    argv = [
        "envmap",
        "--env",
        str(path),
        "--to",
        "cube",
        "--size",
        "0",
        "-o",
        str(tmp_path / "x.exr"),
    ]
    assert main(argv) == 2
    assert "--size 0" in capsys.readouterr().err
