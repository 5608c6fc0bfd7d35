"""Issue 38 (items 3, 11, 12, 13): bad inputs, each run as a user would, counted clean or not.

A case is clean when it gives the right exit status, at most one line on stderr and no
traceback, loses nothing and, for a cache, heals (the next run is silent). The cases:

- option defaults: ``prefilter`` and ``envmap`` with a default that the other options'
  valid values used to make invalid (``--levels`` for a small ``--chain``, ``--size``
  for a wide paraboloid ``--border``);
- the PEM orbit cache: a view truncated, bit-flipped, empty or replaced by a folder,
  ``shell.npz`` cut, bit-flipped or replaced by a folder, a resume part cut (its view
  not yet kept). One view is baked once
  (``render --method pem`` at the scene camera, a 20° orbit uncoupled, about 5 s on
  llvmpipe), copied and damaged for each case, then rendered twice;
- scene files with a misspelt key in every table of the schema: "did you mean";
- ``settings.json``: corrupt in a read-only folder, and a missing folder under a
  read-only one (a read-only bind mount as root, else a folder without write
  permission).

Usage: ``python studies/reliability-audit/files.py`` (about a minute and a half).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ENV = ROOT / "assets" / "hdr" / "studio.exr"
ORBIT = ["coverage=orbit", "orbit_step=20", "orbit_coupling=0", "orbit_fit=seed003"]


def envstudio(*argv: str, cache: Path | None = None, **env: str) -> tuple[int, str]:
    """Run ``envstudio argv`` in a child process; its exit status and stderr."""
    environment = {**os.environ, **env, "PYTHONPATH": str(ROOT / "app")}
    if cache is not None:
        environment["ENVSTUDIO_CACHE_DIR"] = str(cache)
    done = subprocess.run(
        [sys.executable, "-m", "envstudio", *argv],
        capture_output=True,
        text=True,
        env=environment,
        check=False,
    )
    return done.returncode, done.stderr


def python(code: str, **env: str) -> tuple[int, str, str]:
    """Run ``code`` in a child Python; its exit status, stdout and stderr."""
    environment = {**os.environ, **env, "PYTHONPATH": str(ROOT / "app")}
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=environment, check=False
    )
    return done.returncode, done.stdout, done.stderr


def one_line(err: str) -> bool:
    """At most one line and no traceback."""
    return "Traceback" not in err and len(err.strip().splitlines()) <= 1


def option_defaults(tmp: Path) -> list[tuple[str, bool, str]]:
    """Commands whose defaults meet other options' valid values: each must run (status 0)."""
    cases = {
        "prefilter --chain ggx --size 64 (default --levels)": [
            "prefilter", "--env", str(ENV), "--max-env-width", "64", "--chain",
            "--kernel", "ggx", "--param", "cube", "--size", "64", "-o", str(tmp / "g.ktx2"),
        ],
        "prefilter --chain phong --size 16 (default --levels)": [
            "prefilter", "--env", str(ENV), "--max-env-width", "64", "--chain",
            "--param", "cube", "--size", "16", "-o", str(tmp / "p.dds"),
        ],
        "prefilter paraboloid --border 70 (default --size)": [
            "prefilter", "--env", str(ENV), "--max-env-width", "64", "--kernel", "diffuse",
            "--border", "70", "-o", str(tmp / "b.exr"),
        ],
        "envmap paraboloid --border 140 (default --size)": [
            "envmap", "--env", str(ENV), "--max-env-width", "64", "--to", "paraboloid",
            "--border", "140", "-o", str(tmp / "e.exr"),
        ],
    }  # fmt: skip
    rows = []
    for name, argv in cases.items():
        status, err = envstudio(*argv)
        rows.append((name, status == 0 and one_line(err), err.strip()[-160:]))
    return rows


def _render(cache: Path, out: Path) -> tuple[int, str]:
    params = [a for p in ORBIT for a in ("--param", p)]
    argv = ["render", "--method", "pem", "--scene", "room", *params, "--size", "16x16"]
    return envstudio(*argv, "-o", str(out), cache=cache)


def _flip(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x40
    path.write_bytes(bytes(data))


def _folder(path: Path) -> None:
    path.unlink()
    path.mkdir()
    (path / "x").write_bytes(b"x")


def _cut(path: Path) -> None:
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 3])


def orbit_cache(tmp: Path) -> list[tuple[str, bool, str]]:
    """Each corruption of a baked orbit: one note, baked again, the next run silent."""
    base = tmp / "cache"
    status, err = _render(base, tmp / "orbit.png")
    if status:
        return [("orbit: the first bake", False, err.strip()[-160:])]
    (orbit,) = (base / "pem").glob("orbit-*")
    view = sorted((orbit / "views").glob("view-*.pem"))[0].relative_to(base)
    shell = (orbit / "shell.npz").relative_to(base)
    part = (orbit / "orbit.pem.parts" / view.name.replace(".pem", ".npz")).relative_to(base)

    def part_cut(path: Path) -> None:  # a crash after the view's part, before its file
        (base.parent / "damaged" / view).unlink()
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"PK\x03\x04" + b"\0" * 40)

    cases = {
        "view truncated": (view, lambda p: p.write_bytes(p.read_bytes()[:1000])),
        "view bit-flipped": (view, _flip),
        "view empty": (view, lambda p: p.write_bytes(b"")),
        "view a folder": (view, _folder),
        "shell.npz cut": (shell, _cut),
        "shell.npz bit-flipped": (shell, _flip),
        "shell.npz a folder": (shell, _folder),
        "resume part cut": (part, part_cut),
    }
    rows = []
    for name, (where, damage) in cases.items():
        cache = tmp / "damaged"
        shutil.rmtree(cache, ignore_errors=True)
        shutil.copytree(base, cache)
        damage(cache / where)
        first, err1 = _render(cache, tmp / "first.png")
        second, err2 = _render(cache, tmp / "second.png")
        healed = (cache / (view if "part" in name else where)).is_file()
        noted = "note:" in err1 and one_line(err1)
        clean = first == 0 and noted and second == 0 and not err2.strip() and healed
        rows.append((f"orbit: {name}", clean, (err1.strip() or err2.strip())[-160:]))
    return rows


SCENE = """name = "audit"
[environment]
file = "hdr/studio.exr"
[camera]
azimuth = 10.0
[proxy]
shape = "sphere"
centre = [0.0, 0.0, 0.0]
radius = 3.0
[[object]]
primitive = "sphere"
[object.material]
kd = 0.1
"""

#: A key of each table misspelt, placed after the table's header line.
MISSPELT = {
    "top level": ("name = ", 'nmae = "x"\nname = '),
    "environment": ('file = "hdr', 'fiel = "y"\nfile = "hdr'),
    "camera": ("azimuth", "azimuht = 1.0\nazimuth"),
    "proxy": ("radius = 3.0", "radius = 3.0\nraduis = 2.0"),
    "object": ('primitive = "sphere"', 'primitive = "sphere"\nrotaton = [0.0, 0.0, 0.0]'),
    "object.material": ("kd = 0.1", "kd = 0.1\nfrensel = 0.5"),
}


def scene_files(tmp: Path) -> list[tuple[str, bool, str]]:
    """A misspelt key in every table: status 2, one line naming it with "did you mean"."""
    rows = []
    for table, (old, new) in MISSPELT.items():
        path = tmp / f"scene-{table.replace('.', '-').replace(' ', '-')}.toml"
        path.write_text(SCENE.replace(old, new, 1))
        status, err = envstudio(
            "render", "--scene", str(path), "--size", "8x8", "-o", str(tmp / "s.png")
        )
        clean = status == 2 and one_line(err) and "did you mean" in err
        rows.append((f"scene: unknown key in {table}", clean, err.strip()[-160:]))
    return rows


@contextlib.contextmanager
def read_only(folder: Path):
    """``folder`` read-only for this block: a read-only bind mount as root, else no write bit."""
    if os.geteuid() == 0:
        subprocess.run(["mount", "--bind", "-o", "ro", str(folder), str(folder)], check=True)
        try:
            yield
        finally:
            subprocess.run(["umount", str(folder)], check=True)
    else:
        folder.chmod(0o555)
        try:
            yield
        finally:
            folder.chmod(0o755)


SETTINGS = """
from envstudio.ui.settings import load_settings, save_settings
settings, warning = load_settings()
print(warning)
try:
    save_settings(settings)
except Exception as exc:  # a one-line error is what the viewer would print
    from envstudio.errors import UserError
    if not isinstance(exc, UserError):
        raise
"""


def settings(tmp: Path) -> list[tuple[str, bool, str]]:
    """Read-only config folders: defaults, one line saying nothing will be saved, no traceback."""
    corrupt = tmp / "config"
    corrupt.mkdir()
    (corrupt / "settings.json").write_text("{not json")
    outer = tmp / "outer"
    outer.mkdir()
    rows = []
    for name, folder, config in (
        ("settings: corrupt in a read-only folder", corrupt, corrupt),
        ("settings: folder missing under a read-only one", outer, outer / "envstudio"),
    ):
        with read_only(folder):
            status, out, err = python(SETTINGS, ENVSTUDIO_CONFIG_DIR=str(config))
        kept = not (corrupt / "settings.json").exists() or (
            (corrupt / "settings.json").read_text() == "{not json"
        )
        clean = status == 0 and "not be saved" in out and one_line(err) and kept
        rows.append((name, clean, (err.strip() or out.strip())[-160:]))
    return rows


def main() -> int:
    """Run every case; print each and the counts."""
    with tempfile.TemporaryDirectory() as name:
        tmp = Path(name)
        rows = []
        for group in (option_defaults, orbit_cache, scene_files, settings):
            folder = tmp / group.__name__
            folder.mkdir()
            rows += group(folder)
    for name, clean, detail in rows:
        print(f"{'clean' if clean else 'NOT CLEAN':9}  {name}" + ("" if clean else f": {detail}"))
    good = sum(clean for _, clean, _ in rows)
    print(f"{good} clean, {len(rows) - good} not clean, of {len(rows)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
