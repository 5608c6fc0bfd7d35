"""Issue 38 items 5 and 6: the Python API refuses bad arguments in one line, and no failed
call, refused or broken inside the GL work, leaves the process's context or a scene unusable."""

from __future__ import annotations

import math

import numpy as np
import pytest

import envstudio as es
from envstudio import api
from envstudio.measure.compare import method_classes, plan_parameters, run_comparison

SIZE = (16, 16)
CHEAP = {"size": SIZE, "ssaa": 1, "frames": 1, "cache": False, "max_samples": 16}
IMAGE = np.full((4, 4, 3), 0.5, np.float32)


@pytest.fixture(scope="module")
def studio():
    return es.load_scene("studio")


@pytest.fixture(scope="module")
def fresh(studio):
    """The good render every failed call is followed by, as a fresh process makes it."""
    return es.render(studio, "mirror", size=SIZE)


def _compare(scene, methods=("mirror",), **changes):
    return es.compare(scene, methods, **CHEAP | changes)


BAD_CALLS = {
    # item 5: the calls that poisoned the context
    "scene as a string": (lambda s: es.render("studio", "mirror", size=SIZE), "scene 'studio'"),
    "ssaa 0": (lambda s: _compare(s, ssaa=0), "ssaa 0"),
    # item 6: tracebacks
    "size inf": (lambda s: es.render(s, "mirror", size=(math.inf, 32)), "size (inf, 32)"),
    "camera 5": (lambda s: es.render(s, "mirror", size=SIZE, camera=5), "camera 5"),
    "fresnel a,b,c": (lambda s: es.render(s, "mirror", size=SIZE, fresnel=list("abc")), "fresnel"),
    "scene 123": (lambda s: es.load_scene(123), "name_or_path 123"),
    "env 5": (lambda s: es.load_scene(env=5), "env 5"),
    "max_env_width x": (lambda s: es.load_scene(max_env_width="x"), "max_env_width 'x'"),
    "exposure x": (lambda s: es.display(IMAGE, exposure="x"), "exposure=x"),
    "exposure None": (lambda s: es.display(IMAGE, exposure=None), "exposure=None"),
    "display a string": (lambda s: es.display("x"), "image 'x'"),
    "show a string": (lambda s: es.show("x"), "image 'x'"),
    "show 5 channels": (lambda s: es.show(np.zeros((4, 4, 5), np.uint8)), "(4, 4, 5) uint8"),
    "ssaa -1": (lambda s: _compare(s, ssaa=-1), "ssaa -1"),
    "ssaa x": (lambda s: _compare(s, ssaa="x"), "ssaa 'x'"),
    "frames 0": (lambda s: _compare(s, frames=0), "frames 0"),
    # item 6: accepted silently
    "size '32'": (lambda s: es.render(s, "mirror", size="32"), "size '32'"),
    "display 2-D": (lambda s: es.display(IMAGE[..., 0]), "image of shape (4, 4) float32"),
    "display NaN": (lambda s: es.display(IMAGE * np.nan), "finite"),
    "display None": (lambda s: es.display(None), "image None"),
    "display 0x0": (lambda s: es.display(IMAGE[:0, :0]), "image of shape (0, 0, 3)"),
    "show None": (lambda s: es.show(None), "image None"),
    "compare no methods": (lambda s: _compare(s, methods=[]), "methods []"),
    # the same families
    "size (8.5, 8)": (lambda s: es.render(s, "mirror", size=(8.5, 8)), "size (8.5, 8)"),
    "camera (1, 2)": (lambda s: es.render(s, "mirror", size=SIZE, camera=(1, 2)), "camera (1, 2)"),
    "fresnel {}": (lambda s: es.render(s, "mirror", size=SIZE, fresnel={}), "fresnel={}"),
    "method 5": (lambda s: es.render(s, 5, size=SIZE), "method 5"),
    "time_limit x": (
        lambda s: es.render(s, "reference", size=SIZE, time_limit="x"),
        "time_limit x",
    ),
    "display 1e300": (lambda s: es.display(np.full((4, 4, 3), 1e300)), "within"),
    "methods None": (lambda s: _compare(s, methods=None), "methods None"),
    "cache x": (lambda s: _compare(s, cache="x"), "cache 'x'"),
    "compare camera 5": (lambda s: _compare(s, camera=5), "camera 5"),
    # an operating-system error on a named file (here a name too long for the file system)
    "scene name too long": (lambda s: es.load_scene("x" * 300), "xxxxxxxx"),
    "mesh name too long": (lambda s: es.load_scene(mesh="x" * 300 + ".obj"), "xxxxxxxx"),
    # refused inside the GL work, after the methods rendered
    "no reflector in view": (lambda s: _compare(s, camera=(0, 0, 1e6)), "sees no reflector"),
}


@pytest.mark.parametrize("case", BAD_CALLS)
def test_a_bad_call_raises_one_line_and_the_next_render_equals_a_fresh_one(studio, fresh, case):
    call, names = BAD_CALLS[case]
    with pytest.raises(es.UserError) as info:
        call(studio)
    message = str(info.value)
    assert names in message and "\n" not in message
    np.testing.assert_array_equal(es.render(studio, "mirror", size=SIZE), fresh)


def test_any_exception_inside_the_gl_work_leaves_no_broken_session(studio, fresh):
    """Past the boundary, a GL error (an invalid framebuffer) or any exception frees the
    half-built session and is the error reported; the next call starts from a fresh one."""
    plan = plan_parameters(method_classes(["mirror"]), [])
    with pytest.raises(Exception, match="invalid color attachment"):
        with api._session(studio) as session:  # compare's frame at ssaa 0, past its check
            run_comparison(session, ["mirror"], SIZE, plan, frames=1, ssaa=0)
    np.testing.assert_array_equal(es.render(studio, "mirror", size=SIZE), fresh)
    with pytest.raises(KeyboardInterrupt):
        with api._session(studio) as session:
            session.method("kautz")
            raise KeyboardInterrupt
    np.testing.assert_array_equal(es.render(studio, "mirror", size=SIZE), fresh)


def test_a_failed_call_on_another_scene_keeps_both_usable(studio, fresh):
    room = es.load_scene("room")
    room_fresh = es.render(room, "mirror", size=SIZE)
    with pytest.raises(es.ParameterError):
        _compare(room, camera=(0, 0, 1e6))
    np.testing.assert_array_equal(es.render(studio, "mirror", size=SIZE), fresh)
    np.testing.assert_array_equal(es.render(room, "mirror", size=SIZE), room_fresh)


def test_a_call_places_its_own_camera_and_leaves_the_scene_s_alone(studio, fresh):
    home = (studio.camera.azimuth, studio.camera.elevation, studio.camera.distance)
    turned = es.render(studio, "mirror", size=SIZE, camera=(90, 10, 4))
    assert not np.array_equal(turned, fresh)
    assert (studio.camera.azimuth, studio.camera.elevation, studio.camera.distance) == home


def test_good_arguments_of_every_accepted_form_render(studio):
    """What the declarations accept: numpy numbers, a colour as a list or a preset's name,
    a bool, methods as ``--methods`` text, uint8 RGBA shown as is."""
    img = es.render(studio, "mirror", size=np.array([12, 8]), camera=(np.float32(30), 5, 3))
    assert img.shape == (8, 12, 3)
    grey = es.render(studio, "mirror", size=SIZE, fresnel=[0.5, 0.5, 0.5], background=False)
    assert np.array_equal(
        grey, es.render(studio, "mirror", size=SIZE, fresnel="0.5,0.5,0.5", background="false")
    )
    assert es.render(studio, "mirror", size=SIZE, fresnel="gold").shape == (16, 16, 3)
    assert es.display(img, exposure=np.float64(1), tonemap="none").shape == (8, 12, 3)
    assert es.show(np.zeros((2, 3, 4), np.uint8)).pixels.shape == (2, 3, 4)
    assert [row["method"] for row in _compare(studio, methods="mirror, kautz").table] == [
        "mirror",
        "kautz",
    ]
