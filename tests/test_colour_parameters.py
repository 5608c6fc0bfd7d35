"""f_λ and k_d as colours (issue 28): parsing, presets, scene files, `methods --json`, the panel."""

import json

import pytest

from envstudio.cli import main
from envstudio.core.parameters import ParameterValues
from envstudio.core.presets import FRESNEL_PRESETS, FRESNEL_RGB, fresnel_parameter, kd_parameter
from envstudio.engine.registry import available_methods
from envstudio.engine.session import material_values
from envstudio.errors import InputFileError, ParameterError
from envstudio.io.scene_file import load_scene
from envstudio.ui.parameter_widgets import parameter_widgets, scaled_color
from envstudio.ui.status import StatusLine
from test_bad_input import assert_one_line_error, run_cli
from test_imgui_gl import draw_frame, gui, imgui_ctx  # noqa: F401 (fixtures)
from test_scene_file import write_scene


def _values() -> ParameterValues:
    return ParameterValues([fresnel_parameter(1.0), kd_parameter(0.0)])


@pytest.mark.parametrize(
    ("text", "rgb"),
    [
        ("0.5", (0.5, 0.5, 0.5)),  # one number: a grey, as before colours
        (0.25, (0.25, 0.25, 0.25)),
        ("1,0.71,0.29", (1.0, 0.71, 0.29)),
        (" 0.1 , 0.2 , 0.3 ", (0.1, 0.2, 0.3)),
        ((0.1, 0.2, 0.3), (0.1, 0.2, 0.3)),
        ("gold", (1.0, 0.71, 0.29)),
        ("Copper", (0.95, 0.64, 0.54)),
    ],
)
def test_fresnel_takes_a_grey_three_numbers_or_a_preset(text, rgb):
    values = _values()
    values["fresnel"] = text
    assert values["fresnel"] == pytest.approx(rgb)


@pytest.mark.parametrize("text", ["1,2", "1,0.5,1.5", "red", "0.1,0.2,nan", "", "-0.1"])
def test_a_bad_colour_names_the_value_and_what_was_expected(text):
    values = _values()
    with pytest.raises(ParameterError) as info:
        values["fresnel"] = text
    message = str(info.value)
    assert "\n" not in message
    assert f"fresnel={text}" in message and "r,g,b or one number" in message
    assert "gold" in message, "the presets are named"
    with pytest.raises(ParameterError, match=r"kd=red: expected r,g,b .* in \[0, 1\]$"):
        values["kd"] = "red"


def test_a_bad_colour_on_the_command_line_is_one_line(capsys):
    status, err = run_cli(capsys, "render", "--param", "fresnel=1,0.5", "-o", "OUT.png")
    assert_one_line_error(status, err, "fresnel=1,0.5", "r,g,b or one number", "gold")


def test_every_method_declares_fresnel_and_kd_as_colours_with_the_presets(capsys):
    for cls in available_methods().values():
        declared = {p.name: p for p in cls.parameters}
        for name in ("fresnel", "kd"):
            if name in declared:
                assert declared[name].kind == "color", (cls.name, name)
        if "fresnel" in declared:
            assert dict(declared["fresnel"].presets) == FRESNEL_RGB, cls.name
    assert main(["methods", "--json"]) == 0
    described = json.loads(capsys.readouterr().out)
    mirror = next(m for m in described["methods"] if m["name"] == "mirror")
    fresnel = next(p for p in mirror["parameters"] if p["name"] == "fresnel")
    assert fresnel["kind"] == "color" and fresnel["default"] == [1.0, 1.0, 1.0]
    assert fresnel["presets"]["gold"] == [1.0, 0.71, 0.29]


def test_every_preset_is_a_cited_reflectance_in_range():
    assert {"gold", "silver", "copper", "aluminium", "plastic", "glass"} <= set(FRESNEL_RGB)
    for preset in FRESNEL_PRESETS:
        assert len(preset.f0) == 3 and all(0.0 < c <= 1.0 for c in preset.f0), preset
        assert "Table 1" in preset.row, preset


@pytest.mark.parametrize(
    ("text", "rgb"),
    [
        ("fresnel = 0.5", (0.5, 0.5, 0.5)),
        ("fresnel = 1", (1.0, 1.0, 1.0)),
        ("fresnel = [1.0, 0.71, 0.29]", (1.0, 0.71, 0.29)),
        ('fresnel = "silver"', (0.95, 0.93, 0.88)),
    ],
)
def test_scene_files_take_fresnel_as_a_number_three_numbers_or_a_preset(tmp_path, text, rgb):
    scene = load_scene(write_scene(tmp_path, text + "\nkd = [0.1, 0.2, 0.3]"))
    assert scene.reflectors()[0].material.fresnel == pytest.approx(rgb)
    values = material_values(scene)
    assert values["fresnel"] == pytest.approx(rgb)
    assert values["kd"] == pytest.approx((0.1, 0.2, 0.3)), "k_d stays a colour"


@pytest.mark.parametrize(
    ("text", "fragments"),
    [
        ('fresnel = "golf"', ["material.fresnel = 'golf'", "gold, silver"]),
        ("fresnel = 1.5", ["material.fresnel = 1.5", "[0, 1]", "preset"]),
        ("fresnel = [1, 0.5]", ["material.fresnel = [1, 0.5]", "three numbers"]),
    ],
)
def test_a_bad_scene_file_fresnel_is_one_line(tmp_path, text, fragments):
    with pytest.raises(InputFileError) as info:
        load_scene(write_scene(tmp_path, text))
    message = str(info.value)
    assert "\n" not in message and "scene.toml" in message
    for fragment in fragments:
        assert fragment in message, message


def test_the_scalar_slider_scales_the_colour():
    assert scaled_color((1.0, 0.5, 0.0), 0.25, 1.0) == pytest.approx((0.5, 0.25, 0.0))
    assert scaled_color((0.0, 0.0, 0.0), 0.3, 1.0) == (0.3, 0.3, 0.3), "black becomes a grey"
    assert scaled_color((1.0, 0.71, 0.29), 0.9, 1.0) == pytest.approx((1.0, 0.9585, 0.3915))


def test_the_panel_draws_a_colour_editor_a_slider_and_presets(gui):  # noqa: F811 (fixture)
    values = _values()
    values["fresnel"] = "gold"
    status = StatusLine()
    pixels = draw_frame(gui, lambda: parameter_widgets(values, status))
    assert pixels.any()
    assert values["fresnel"] == (1.0, 0.71, 0.29), "drawing changes nothing"
    assert values.revision == 1
