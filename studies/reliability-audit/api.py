"""Reliability audit of the Python API (issue 38 items 5, 6): bad calls, then a good render.

Each bad call is counted clean when it raises a ``UserError`` with a one-line message and the
next good render equals the fresh one made first; not clean when it raises anything else (a
traceback), returns (accepted silently) or leaves the next render failing or different. The
``--param`` strings go through ``envstudio render``: clean is exit 2 and no exception.

Run ``python studies/reliability-audit/api.py`` from the repository root.

Record (issue 38 items 5, 6): before the fix 29 clean, 28 not of the first 57 cases (the three
added later, ``display(1e300)`` and the two 300-character file names, not clean as well);
after it 58 clean, 2 not: the 300-character names still ended in ``OSError`` (File name too
long) inside io/scene_file.py and io/meshes.py, as ``envstudio render --scene`` did; with an
OS error on a named file made one line at the CLI's and the API's boundary, 60 clean, 0 not.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

import envstudio as es
from envstudio import api
from envstudio.cli import main as cli

SIZE = (16, 16)
CHEAP = {"size": SIZE, "ssaa": 1, "frames": 1, "cache": False, "max_samples": 16}


def bad_calls(scene, img):
    """Name → a call that must raise a UserError."""
    return {
        "render('studio', ...)": lambda: es.render("studio", "mirror", size=(32, 32)),
        "render(method=5)": lambda: es.render(scene, 5, size=SIZE),
        "render(method='phong')": lambda: es.render(scene, "phong", size=SIZE),
        "render(size=(inf, 32))": lambda: es.render(scene, "mirror", size=(math.inf, 32)),
        "render(size='32')": lambda: es.render(scene, "mirror", size="32"),
        "render(size=None)": lambda: es.render(scene, "mirror", size=None),
        "render(size=(8.5, 8))": lambda: es.render(scene, "mirror", size=(8.5, 8)),
        "render(size=(0, 8))": lambda: es.render(scene, "mirror", size=(0, 8)),
        "render(camera=5)": lambda: es.render(scene, "mirror", size=SIZE, camera=5),
        "render(camera=(1, 2))": lambda: es.render(scene, "mirror", size=SIZE, camera=(1, 2)),
        "render(camera=abc)": lambda: es.render(scene, "mirror", size=SIZE, camera=("a", "b", "c")),
        "render(camera=(0, 100, 3))": lambda: es.render(
            scene, "mirror", size=SIZE, camera=(0, 100, 3)
        ),
        "render(fresnel=['a','b','c'])": lambda: es.render(
            scene, "mirror", size=SIZE, fresnel=["a", "b", "c"]
        ),
        "render(fresnel=None)": lambda: es.render(scene, "mirror", size=SIZE, fresnel=None),
        "render(fresnel=1.5)": lambda: es.render(scene, "mirror", size=SIZE, fresnel=1.5),
        "render(fresnel={})": lambda: es.render(scene, "mirror", size=SIZE, fresnel={}),
        "render(lod_bias=nan) kautz": lambda: es.render(
            scene, "kautz", size=SIZE, lod_bias=math.nan
        ),
        "render(lod_bias=2) mirror": lambda: es.render(scene, "mirror", size=SIZE, lod_bias=2),
        "render(exposure='x')": lambda: es.render(scene, "mirror", size=SIZE, exposure="x"),
        "render(time_limit=-1) reference": lambda: es.render(
            scene, "reference", size=SIZE, time_limit=-1
        ),
        "render(time_limit='x') reference": lambda: es.render(
            scene, "reference", size=SIZE, time_limit="x"
        ),
        "render(time_limit=5) mirror": lambda: es.render(scene, "mirror", size=SIZE, time_limit=5),
        "load_scene(123)": lambda: es.load_scene(123),
        "load_scene(env=5)": lambda: es.load_scene(env=5),
        "load_scene(mesh=5)": lambda: es.load_scene(mesh=5),
        "load_scene(max_env_width='x')": lambda: es.load_scene(max_env_width="x"),
        "load_scene('nowhere.toml')": lambda: es.load_scene("nowhere.toml"),
        "load_scene('x' * 300)": lambda: es.load_scene("x" * 300),
        "load_scene(mesh='x' * 300)": lambda: es.load_scene(mesh="x" * 300),
        "display(exposure='x')": lambda: es.display(img, exposure="x"),
        "display(exposure=None)": lambda: es.display(img, exposure=None),
        "display(tonemap=5)": lambda: es.display(img, tonemap=5),
        "display('x')": lambda: es.display("x"),
        "display(2-D)": lambda: es.display(img[..., 0]),
        "display(NaN)": lambda: es.display(np.full((4, 4, 3), np.nan, np.float32)),
        "display(None)": lambda: es.display(None),
        "display(1e300)": lambda: es.display(np.full((4, 4, 3), 1e300)),
        "display(0x0)": lambda: es.display(np.zeros((0, 0, 3), np.float32)),
        "show('x')": lambda: es.show("x"),
        "show(5-channel uint8)": lambda: es.show(np.zeros((4, 4, 5), np.uint8)),
        "show(None)": lambda: es.show(None),
        "compare(ssaa=0)": lambda: es.compare(scene, ["mirror"], **CHEAP | {"ssaa": 0}),
        "compare(ssaa=-1)": lambda: es.compare(scene, ["mirror"], **CHEAP | {"ssaa": -1}),
        "compare(ssaa='x')": lambda: es.compare(scene, ["mirror"], **CHEAP | {"ssaa": "x"}),
        "compare(frames=0)": lambda: es.compare(scene, ["mirror"], **CHEAP | {"frames": 0}),
        "compare(scene, [])": lambda: es.compare(scene, [], **CHEAP),
        "compare(methods=None)": lambda: es.compare(scene, None, **CHEAP),
        "compare(cache='x')": lambda: es.compare(scene, ["mirror"], **CHEAP | {"cache": "x"}),
        "compare(camera=5)": lambda: es.compare(scene, ["mirror"], **CHEAP | {"camera": 5}),
        "compare(size=(4, 4))": lambda: es.compare(scene, ["mirror"], **CHEAP | {"size": (4, 4)}),
    }


BAD_PARAMS = ["lod_bias", "=2", "lod_bias=nan", "lod_bias=1e400", "fresnel=1,2", "kd=a,b,c"]
BAD_PARAMS += ["background=maybe", "tonemap=", "exposure=inf", "nothing=1"]


def outcome(call) -> str:
    """``clean`` or what went wrong."""
    try:
        call()
    except es.UserError as exc:
        return "clean" if "\n" not in str(exc) else f"multi-line message: {exc!r}"
    except Exception as exc:
        return f"traceback: {type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"
    return "accepted silently"


def next_render(scene, fresh) -> str | None:
    """None when a good render still equals the fresh one, else what went wrong."""
    try:
        again = es.render(scene, "mirror", size=SIZE)
    except Exception as exc:
        return f"poisoned: {type(exc).__name__}: {exc}"
    return None if np.array_equal(again, fresh) else "poisoned: the next render differs"


def cli_param(param: str, out: Path) -> str:
    """``envstudio render --param param``: exit 2 without an exception is clean."""
    argv = ["render", "--method", "kautz", "--size", "8x8", "--param", param, "-o", str(out)]
    try:
        with contextlib.redirect_stderr(io.StringIO()), contextlib.redirect_stdout(io.StringIO()):
            code = cli(argv)
    except Exception as exc:
        return f"traceback: {type(exc).__name__}: {exc}"
    return "clean" if code == 2 else f"exit {code}"


def main() -> int:
    scene = es.load_scene("studio")
    fresh = es.render(scene, "mirror", size=SIZE)
    verdicts = {
        name: lambda call=call: outcome(call) for name, call in bad_calls(scene, fresh).items()
    }
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "x.png"
        verdicts |= {f"--param {p!r}": lambda p=p: cli_param(p, out) for p in BAD_PARAMS}
        results = []
        for name, verdict in verdicts.items():  # each bad call, then a good render
            result = verdict()
            poisoned = next_render(scene, fresh)
            if poisoned:  # a fresh API (a new context and session) for the next case
                importlib.reload(api)
            results.append((name, poisoned or result))
    for name, result in results:
        print(f"{'clean' if result == 'clean' else 'NOT  '}  {name}: {result}")
    clean = sum(result == "clean" for _, result in results)
    print(f"\nclean {clean}, not clean {len(results) - clean}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
