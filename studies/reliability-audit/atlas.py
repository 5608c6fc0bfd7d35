"""Reliability audit of ``envstudio atlas`` (issue 38): bad input, corrupt folders, races.

Runs the command on a one-cell grid and counts each case clean or not:

* bad grid values: exit 2, one line on stderr, no ``--out`` written (a 1x2
  environment is not one: every method measures it);
* a corrupt entry in an existing ``--out``: exit 0, the entry set aside as
  ``*.corrupt``, every cell measured with its images, ``atlas.json`` strict JSON;
* a failed cell: measured again once its input is fixed;
* two identical runs at once: the cell measured once, or one run refused in one line;
* ``compare`` of pem with no bake: says "needs a bake", as the atlas does.

Run ``python studies/reliability-audit/atlas.py`` from the repository root.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from envstudio.io.images import write_image

GRID = "--methods mirror --envs studio --meshes sphere --exponents 10 --size 16x16".split()
GRID += "--time-limit 2 --cameras 1".split()


def atlas(out: Path | str, *extra: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    """``envstudio atlas`` of the tiny grid (``extra`` overrides its options)."""
    return subprocess.run(
        [sys.executable, "-m", "envstudio", "atlas", *GRID, *extra, "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=cwd,
    )


def strict_json(path: Path):
    """``path`` parsed, refusing NaN and Infinity as a browser does."""
    return json.loads(path.read_text(), parse_constant=lambda name: 1 / 0)


def refused(result, out: Path) -> bool:
    """Exit 2, one line, no traceback, nothing written."""
    lines = result.stderr.strip().splitlines()
    return result.returncode == 2 and len(lines) == 1 and not out.exists()


def measured_whole(result, out: Path) -> bool:
    """Exit 0 and every cell measured with its images in a strict atlas.json."""
    if result.returncode != 0 or "Traceback" in result.stderr:
        return False
    try:
        rows = strict_json(out / "atlas.json")["cells"]
    except (OSError, ValueError, ZeroDivisionError, KeyError, TypeError):
        return False
    images = all((out / "cells" / r.get("image", "-")).is_file() for r in rows)
    return len(rows) == 1 and images and all(r.get("error") is None for r in rows)


def env_files(root: Path) -> dict[str, Path]:
    """Environments that must be refused up front."""
    garbage = root / "garbage.exr"
    garbage.write_bytes(b"not an image" * 10)
    eight_bit = write_image(root / "eight.png", np.full((32, 64, 3), 0.5, np.float32))
    eight_bit = eight_bit.rename(root / "eight.exr")  # 8-bit pixels behind an HDR name
    nan = np.ones((32, 64, 3), np.float32)
    nan[3, 4] = np.nan
    return {
        "unreadable": garbage,
        "8-bit": eight_bit,
        "nan": write_image(root / "nan.exr", nan),
    }


def bad_inputs(root: Path) -> dict[str, list[str]]:
    cases = {f"--envs {k}": ["--envs", str(p)] for k, p in env_files(root).items()}
    values = {
        "--exponents": ["inf", "1e300", "1e-300", "nan"],
        "--kd": ["nan"],
        "--time-limit": ["inf", "nan"],
        "--size": ["1x1"],
        "--ssaa": ["0", "-1", "17"],
        "--cameras": ["0"],
    }
    for option, texts in values.items():
        cases |= {f"{option} {t}": [option, t] for t in texts}
    return cases


def corrupt(out: Path, target: str, kind: str) -> None:
    """Spoil one entry of a measured atlas folder."""
    cell = next((out / "cells").glob("*.json"))
    path = {"settings": out / "atlas-settings.json", "cell": cell, "atlas": out / "atlas.json"}
    path = path.get(target)
    if target == "cells":
        shutil.rmtree(out / "cells")
        (out / "cells").write_text("x")
        return
    if target == "pngs":
        for png in cell.with_suffix("").glob("*.png"):
            png.unlink()
        return
    text = path.read_text()
    path.unlink()
    if kind == "folder":
        path.mkdir()
        return
    content = {
        "truncated": text[: len(text) // 2].encode(),
        "empty": b"",
        "a list": b"[1, 2]",
        "foo rows": b'[{"foo": 1}]',
        "binary": bytes(range(256)),
        "null": b"null",
    }[kind]
    path.write_bytes(content)


def main() -> int:
    clean, dirty = [], []

    def count(name: str, ok: bool) -> None:
        (clean if ok else dirty).append(name)
        print(f"{'clean' if ok else 'NOT  '}  {name}", flush=True)

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for name, extra in bad_inputs(root).items():
            out = root / "bad"
            count(f"refuse {name}", refused(atlas(out, *extra), out))
            shutil.rmtree(out, ignore_errors=True)
        empty = root / "cwd"
        empty.mkdir()
        result = atlas("", cwd=empty)
        count("refuse --out ''", result.returncode == 2 and not any(empty.iterdir()))

        base = root / "base"
        atlas(base)
        kinds = ["truncated", "empty", "a list", "foo rows", "binary", "null", "folder"]
        cases = [(t, k) for t in ("settings", "cell", "atlas") for k in kinds]
        for target, kind in [*cases, ("cells", "a file"), ("pngs", "missing")]:
            out = root / "corrupt"
            shutil.copytree(base, out)
            corrupt(out, target, kind)
            result = atlas(out)
            aside = target in ("atlas", "pngs") or any(out.rglob("*.corrupt"))
            count(f"corrupt {target}: {kind}", measured_whole(result, out) and aside)
            shutil.rmtree(out)

        nan_env = env_files(root)["nan"]
        out = root / "fixed"
        atlas(out, "--envs", str(nan_env))
        fixed = np.ones((32, 64, 3), np.float32)
        write_image(nan_env, fixed)
        count(
            "failed cell measured once fixed",
            measured_whole(atlas(out, "--envs", str(nan_env)), out),
        )
        out = root / "failed"
        shutil.copytree(base, out)
        cell = next((out / "cells").glob("*.json"))
        rows = json.loads(cell.read_text())
        cell.write_text(json.dumps([rows[0] | {"error": "old"}]))
        count("failed row measured again", measured_whole(atlas(out), out))

        out = root / "race"
        command = [sys.executable, "-m", "envstudio", "atlas", *GRID, "--out", str(out)]
        runs = [
            subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for _ in range(2)
        ]
        results = [(r.communicate(), r.returncode) for r in runs]
        results = [(rc, out_text, err) for (out_text, err), rc in results]
        measured = sum(
            int(o.split("(")[1].split()[0]) for rc, o, _ in results if rc == 0 and "(" in o
        )
        lock = [e for rc, _, e in results if rc == 2 and len(e.strip().splitlines()) == 1]
        count(
            "two runs at once",
            measured == 1 and (len(lock) == 1 or all(rc == 0 for rc, *_ in results)),
        )

        result = subprocess.run(
            [
                sys.executable,
                "-m",
                "envstudio",
                "compare",
                "--methods",
                "pem",
                "--scene",
                "studio",
                "--size",
                "16x16",
                "--time-limit",
                "2",
                "--out",
                str(root / "cmp"),
            ],
            capture_output=True,
            text=True,
        )
        count("compare pem without a bake", "needs a bake" in result.stdout + result.stderr)
    print(f"\nclean {len(clean)}, not clean {len(dirty)}")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONWARNINGS", "ignore")
    sys.exit(main())
