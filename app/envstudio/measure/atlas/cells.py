"""Measure the cells of one scene: one fair ``compare`` run (measure.compare)."""

from __future__ import annotations

import math
from pathlib import Path

from envstudio.errors import ParameterError
from envstudio.io.meshes import load_mesh
from envstudio.io.scene_file import shipped_environments
from envstudio.io.scene_setup import build_scene, replace_reflector
from envstudio.measure.atlas.grid import SceneCell
from envstudio.measure.atlas.memory import gpu_bytes
from envstudio.measure.atlas.sessions import KEPT
from envstudio.measure.compare import method_classes, plan_parameters, run_comparison
from envstudio.measure.report import write_report
from envstudio.resources import asset_root
from envstudio.scene.graph import Scene
from envstudio.scene.primitives import torus_knot, uv_sphere

__all__ = ["TIMING_BASELINE", "cell_scene", "measure_scene_cell", "resolve_env", "resolve_mesh"]

#: The method every cost is a ratio to (measured in every scene, listed only if asked for).
TIMING_BASELINE = "mirror"
#: Timed and untimed frames per method.
FRAMES, WARMUP = 5, 1


def resolve_env(name: str) -> Path:
    """A shipped environment name or an .exr/.hdr path; ParameterError if neither."""
    shipped = shipped_environments()
    if name in shipped:
        return shipped[name]
    path = Path(name)
    if path.suffix.lower() not in (".exr", ".hdr") or not path.is_file():
        raise ParameterError(
            f"--envs {name}: not a shipped environment ({', '.join(shipped)}) nor an .exr/.hdr file"
        )
    return path


def resolve_mesh(name: str):
    """``sphere``, ``knot``, ``bunny`` or a mesh file, fitted into the unit sphere."""
    if name == "sphere":
        return uv_sphere(1.0, 64, 128)
    if name == "knot":
        return torus_knot().fitted(1.0)
    if name == "bunny":
        return load_mesh(asset_root() / "mesh" / "bunny.ply").fitted(1.0)
    path = Path(name)
    if not path.is_file():
        raise ParameterError(f"--meshes {name}: expected sphere, knot, bunny or a mesh file")
    return load_mesh(path).fitted(1.0)


def cell_scene(cell: SceneCell, cameras: int) -> Scene:
    """The studio scene with the cell's environment, reflector and camera k of K."""
    scene = build_scene(None, resolve_env(cell.env))
    scene.nodes = replace_reflector(scene, resolve_mesh(cell.mesh))
    scene.variant = f"env {Path(cell.env).name}, mesh {Path(cell.mesh).name}"
    scene.camera.azimuth = (scene.camera.azimuth + 360.0 * cell.camera / cameras) % 360.0
    return scene


def measure_scene_cell(
    cell: SceneCell,
    methods: list[str],
    settings: dict,
    folder: Path,
) -> list[dict]:
    """Measure ``methods`` in ``cell``'s scene and write compare's report into ``folder``.

    Parameters
    ----------
    cell
        The scene.
    methods
        The methods to measure (the timing baseline is measured too, listed only if asked).
    settings
        The grid's settings (AtlasGrid.settings).
    folder
        Where the images, heat maps and compare.json go (made if missing).

    Returns
    -------
    list of dict
        One row per method of ``methods``: the cell, the errors (approximation,
        scene, scene only: median relative; PSNR and FLIP against both
        references), ms per frame and its ratio to the baseline, GPU bytes, the
        reference it was measured against, and its image files relative to the
        atlas folder. A method that fails gets a row with its one-line reason
        (``error``); one whose input is missing (MethodResult.missing_input: pem
        without a bake for the scene) a row with ``skipped`` and no numbers, as
        ``compare`` gives it none.
    """
    names = list(dict.fromkeys([*methods, TIMING_BASELINE]))
    classes = method_classes(names)
    assignments = [*settings["params"], f"phong_exponent={cell.exponent:g}", f"kd={cell.kd:g}"]
    plan = plan_parameters(classes, assignments)
    # the session of the scene before where the environment is the same (sessions.py)
    session = KEPT.session_for(cell_scene(cell, settings["cameras"]))
    try:
        comparison = run_comparison(
            session,
            names,
            tuple(settings["size"]),
            plan,
            FRAMES,
            WARMUP,
            cache=True,
            time_limit_s=settings["time_limit"],
            ssaa=settings["ssaa"],
            reference_kind=settings["reference"],
            lobes=KEPT.lobes,
        )
        memory = {name: gpu_bytes(session.method(name)) for name in names}
    except BaseException:
        KEPT.release()  # a scene that failed midway hands nothing on to the next
        raise
    folder.mkdir(parents=True, exist_ok=True)
    write_report(comparison, folder)
    results = {r.name: r for r in comparison.results}
    baseline_ms = results[TIMING_BASELINE].frame_ms["median_ms"]
    rows = []
    for name in methods:
        r = results[name]
        if r.missing_input:
            rows.append(
                {**cell.__dict__, "method": name, "error": None, "skipped": r.missing_input}
            )
            continue
        approximation = r.approximation
        rows.append(
            {
                **cell.__dict__,
                "method": name,
                "reference_model": r.reference_model,
                "approximation_error": _finite(r.approximation_error),
                "scene_error": _finite(r.median_relative_error),
                "scene_only_error": _finite(r.scene_only_error),
                "approximation_psnr_db": _finite(approximation.psnr_db if approximation else None),
                "approximation_flip": _finite(approximation.flip if approximation else None),
                "psnr_db": _finite(r.metrics.psnr_db),
                "flip": _finite(r.metrics.flip),
                "reliable": r.reliable,
                "unreliable_reason": None if r.reliable else _own_reason(comparison, r),
                "ms_per_frame": r.frame_ms["median_ms"],
                "cost_ratio": r.frame_ms["median_ms"] / max(baseline_ms, 1e-9),
                "gpu_bytes": memory[name],
                "image": f"{folder.name}/{name}.png",
                "heat_map": f"{folder.name}/{name}.relerr.png",
                "reference_image": f"{folder.name}/reference.png",
                "error": None,
            }
        )
    return rows


def _own_reason(comparison, result) -> str:
    """Why ``result``'s numbers are marked: its own reference's reason (compare's)."""
    run = comparison.references.get(result.reference_model or "", comparison.reference)
    return run.unreliable_reason or "no reference of its reflectance model"


def failed_rows(cell: SceneCell, methods: list[str], reason: str) -> list[dict]:
    """Rows for methods whose scene could not be measured, with the one-line reason."""
    return [{**cell.__dict__, "method": name, "error": reason} for name in methods]


def _finite(value: float | None) -> float | None:
    """JSON-safe: None for a missing or non-finite number (inf PSNR included)."""
    if value is None or not math.isfinite(value):
        return None
    return float(value)
