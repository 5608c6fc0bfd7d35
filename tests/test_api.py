"""envmap-studio as a library (``import envstudio as es``): the CLI's frames, as arrays."""

from __future__ import annotations

import numpy as np
import pytest

import envstudio as es
from envstudio.cli import main
from envstudio.io.images import HALF_MAX, read_image


@pytest.fixture(scope="module")
def studio():
    return es.load_scene("studio")


def _as_written(image: np.ndarray) -> np.ndarray:
    """What an EXR holds of ``image``: half floats where every value fits, else float32."""
    if np.abs(image).max() <= HALF_MAX:
        return image.astype(np.float16).astype(np.float32)
    return image


def test_render_equals_the_cli_exr_pixel_for_pixel(studio, tmp_path):
    img = es.render(studio, "kautz", size=(48, 40), lod_bias=2.0, camera=(115, 20, 3.2))
    assert img.shape == (40, 48, 3) and img.dtype == np.float32
    out = tmp_path / "kautz.exr"
    argv = ["render", "--method", "kautz", "--param", "lod_bias=2.0", "--camera", "115,20,3.2"]
    assert main([*argv, "--size", "48x40", "-o", str(out)]) == 0
    np.testing.assert_array_equal(_as_written(img), read_image(out))
    # another call starts from the scene's camera and the method's defaults again
    again = es.render(studio, "kautz", size=(48, 40))
    assert main(["render", "--method", "kautz", "--size", "48x40", "-o", str(out)]) == 0
    np.testing.assert_array_equal(_as_written(again), read_image(out))


def test_display_is_the_png_and_show_makes_a_png(studio, tmp_path):
    img = es.render(studio, "mirror", size=(32, 32))
    out = tmp_path / "mirror.png"
    assert main(["render", "--method", "mirror", "--size", "32x32", "-o", str(out)]) == 0
    ldr = es.display(img)
    assert ldr.dtype == np.uint8
    png = np.round(read_image(out)[..., :3] * 255.0)
    assert np.abs(ldr.astype(np.float64) - png).max() <= 1.0  # GPU display shader vs CPU twin
    assert es.show(img)._repr_png_()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda s: es.render(s, "phong"), es.ParameterError, "unknown method 'phong'"),
        (lambda s: es.render(s, "mirror", lod_bias=2), es.ParameterError, "'lod_bias'"),
        (lambda s: es.render(s, "mirror", fresnel=1.5), es.ParameterError, "fresnel=1.5"),
        (lambda s: es.render(s, "mirror", size=(0, 8)), es.ParameterError, "size (0, 8)"),
        (lambda s: es.render(s, "mirror", time_limit=5), es.ParameterError, "one frame"),
        (lambda s: es.load_scene("nowhere.toml"), es.InputFileError, "nowhere.toml"),
    ],
)
def test_bad_input_raises_the_cli_errors(studio, call, error, message):
    with pytest.raises(error, match=None) as info:
        call(studio)
    assert isinstance(info.value, es.UserError) and message in str(info.value)


def _rss_mb() -> float:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * 4096 / 2**20


def test_many_frames_across_methods_hold_memory_flat(studio):
    """One context per process: 200 frames across four methods do not grow the process."""
    methods = ["mirror", "kautz", "hwconv", "rsibr"]
    for name in methods:  # warm-up: programs, maps and bakes made once
        es.render(studio, name, size=(24, 24), map_size=16) if name == "rsibr" else es.render(
            studio, name, size=(24, 24)
        )
    start = _rss_mb()
    for frame in range(200):
        name = methods[frame % len(methods)]
        extra = {"map_size": 16} if name == "rsibr" else {}
        es.render(studio, name, size=(24, 24), **extra)
    assert _rss_mb() - start < 30.0


def test_compare_returns_the_table_the_frames_and_an_html_view(studio):
    report = es.compare(studio, ["mirror"], size=(32, 32), ssaa=1, cache=False, max_samples=16)
    (row,) = report.table
    assert row["method"] == "mirror" and row["reference"] == "phong"
    assert row["psnr_db"] == report.json["methods"]["mirror"]["psnr_db"]
    assert report.images["mirror"].shape == report.reference.shape == (32, 32, 3)
    assert "<table>" in report._repr_html_() and "data:image/png" in report._repr_html_()


def test_a_compare_s_values_do_not_leak_into_the_next(studio):
    """A parameter or display value one call sets is gone at the next: its report equals a
    call that never set it (kautz's per_pixel, the exposure)."""
    args = {"size": (32, 32), "ssaa": 1, "frames": 1, "cache": False, "trace": False}
    plain = es.compare(studio, ["kautz"], **args).json["methods"]["kautz"]
    es.compare(studio, ["kautz"], per_pixel=True, exposure=2.0, **args)
    after = es.compare(studio, ["kautz"], **args)
    assert after.json["display"]["exposure"] == 0.0
    assert after.json["methods"]["kautz"]["parameters"]["per_pixel"] is False
    assert after.json["methods"]["kautz"]["psnr_db"] == plain["psnr_db"]
