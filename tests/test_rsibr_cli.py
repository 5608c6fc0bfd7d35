"""Method ``rsibr``'s out-of-range BRDF parameters (seed 002, issue 17 "Bad input").

The CLI refuses them with one line and writes nothing; the viewer's widgets clamp
them with a note (ui.parameter_widgets.clamp_note).
"""

from __future__ import annotations

import pytest

from envstudio.cli import main
from envstudio.engine.registry import method_class
from envstudio.resources import asset_root
from envstudio.ui.parameter_widgets import clamp_note


@pytest.mark.parametrize(
    "argv",
    [
        ["bake", "rsibr", "--env", "ENV", "--brdf", "phong", "--param", "phong_exponent=9000"],
        ["bake", "rsibr", "--env", "ENV", "--brdf", "carpaint", "--param", "coat_f0=0.5"],
        ["render", "--method", "rsibr", "--param", "phong_exponent=0.5", "--size", "16x16"],
    ],
)
def test_an_out_of_range_brdf_parameter_is_refused_in_one_line(capsys, tmp_path, argv):
    env = str(asset_root() / "hdr" / "studio.exr")
    output = tmp_path / ("out.png" if argv[0] == "render" else "out.rsibr")
    argv = [env if a == "ENV" else a for a in argv]
    tail = ["--size", "16", "-o", str(output)] if argv[0] == "bake" else ["-o", str(output)]
    status = main([*argv, *tail])
    err = capsys.readouterr().err.strip()
    assert status == 2
    assert len(err.splitlines()) == 1, err
    assert "expected a number in" in err
    assert not output.exists()
    assert list(tmp_path.iterdir()) == []


def test_the_ui_clamps_an_out_of_range_value_with_a_note():
    exponent = next(p for p in method_class("rsibr").parameters if p.name == "phong_exponent")
    value, note = clamp_note(exponent, 9000.0)
    assert value == exponent.maximum
    assert note == "phong_exponent 9000 is out of [1, 5000]: clamped to 5000"
    assert clamp_note(exponent, 50.0) == (50.0, None)
    rings = next(p for p in method_class("rsibr").parameters if p.name == "rings")
    assert clamp_note(rings, 1) == (2, "rings 1 is out of [2, 64]: clamped to 2")
