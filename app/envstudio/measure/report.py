"""The files of ``envstudio compare``: images, heat maps, a table (Markdown, JSON) and a page.

Written into one folder, every file atomically::

    reference.exr  reference.png         the reference frame: linear / as displayed
    <method>.exr   <method>.png          each method's frame (not repeated for ``reference``)
    <method>.flip.png                    LDR-FLIP error, magma over [0, 1]
    <method>.relerr.png                  relative luminance error of the linear frames,
                                         magma over [0, HEAT_SCALE] (as the viewer's heat map)
    compare.md   compare.json            the table
    index.html                           the images side by side with the table (relative links)

A method may add sections (methods.base.ReportExtra, from Method.report_extras,
e.g. hwconv's accuracy against the brute-force prefilter): each is a heading, a
sentence, a small table and images it wrote into the folder, rendered after the
table in compare.md and index.html and given under the method's ``extras`` in the
JSON (only for methods that add some).

Heat maps colour only the reflector's pixels; the rest shows the reference
dimmed to grey. In the JSON, PSNR of identical images is the string ``"inf"``
(JSON has no infinity) and numbers are plain floats; ``reliable`` is false and
``unreliable_reason`` says why (null when every method is reliable). A method
whose input is missing (pem without a bake) has no numbers, ``missing_input``
says what it needs (``needs a bake: ...``, as the atlas lists it), and so does
the reason. The
reference's ``stopping_rule`` (``noise``: its noise under a tenth of every
method's error, the default; ``tolerance``: the successive-half change, strict),
``stopped_by`` (``reliable``, ``converged``, ``max_samples``, ``time_limit``) and
``relative_standard_error`` (the noise reached) are stated in the JSON and on the
table's ``reference:`` line. The Markdown table is what the command prints;
unreliable metrics carry a dagger (†) and the reason follows the table.
"""

from __future__ import annotations

import html
import json
import math
import os
from dataclasses import asdict
from pathlib import Path

import numpy as np
import numpy.typing as npt

from envstudio.core.colormap import MAGMA_STOPS, magma
from envstudio.core.env_sampling import LUMINANCE
from envstudio.engine.method import ReportExtra
from envstudio.engine.registry import ground_truth_class
from envstudio.engine.split_view import SplitSettings
from envstudio.io.atomic import check_output_folder, write_text_atomic
from envstudio.io.images import write_image
from envstudio.measure.compare import Comparison, MethodResult
from envstudio.measure.reference_runs import STOPPED_BY, ReferenceRun
from envstudio.measure.stopping import NOISE_RULE, NOISE_SHARE

HEAT_SCALE = SplitSettings().heat_scale
"""Relative error at the top of the colour scale of ``*.relerr.png`` (the viewer's default)."""
CONTEXT_BRIGHTNESS = 0.35
"""Brightness of the grey reference shown around the reflector in heat maps."""
UNRELIABLE = "†"
"""Mark of a metric that cannot be trusted."""

METRIC_NOTES = {
    "domain": "display images (exposure, tone map, sRGB encoding; float, clipped to [0, 1]) "
    "over the reflector pixels (the reference's coverage)",
    "psnr_db": "10 log10(1 / MSE), peak 1; inf when identical",
    "ssim": "scikit-image, Gaussian window sigma 1.5, population covariance, "
    "mean of the SSIM map over the mask",
    "flip": "LDR-FLIP (flip-evaluator, 67 pixels per degree), mean over the mask",
    "errors": "median relative luminance error of the linear frames over the mask; "
    "approximation: against the untraced reference (the environment-map model the "
    "technique approximates); scene: against the traced one (PSNR, SSIM, FLIP too); scene "
    "only: the untraced reference against the traced one, what no environment map shows",
}


def write_report(comparison: Comparison, folder: str | os.PathLike) -> list[Path]:
    """Write every file of the comparison into ``folder`` (made if missing, parent must exist).

    Returns
    -------
    list of Path
        The files written.
    """
    folder = check_output_folder(folder)
    folder.mkdir(exist_ok=True)
    written = []
    for model, run in _references(comparison).items():
        files = _reference_files(comparison, model)
        written.append(write_image(folder / files["exr"], run.hdr))
        written.append(write_image(folder / files["png"], run.display))
    for result in comparison.results:
        files = _files(result.name)
        if result.name != ground_truth_class().name:
            written.append(write_image(folder / files["exr"], result.hdr))
            written.append(write_image(folder / files["png"], result.display))
        reference = _references(comparison).get(result.reference_model, comparison.reference)
        context = CONTEXT_BRIGHTNESS * (reference.display @ LUMINANCE)
        written.append(
            write_image(
                folder / files["flip"],
                heat_map(result.metrics.flip_map, comparison.mask, context),
            )
        )
        written.append(
            write_image(
                folder / files["relerr"],
                heat_map(result.relative_error / HEAT_SCALE, comparison.mask, context),
            )
        )
    for name, text in (
        ("compare.md", format_table(comparison) + "\n"),
        ("compare.json", json.dumps(to_json(comparison), indent=2, allow_nan=False) + "\n"),
        ("index.html", to_html(comparison)),
    ):
        write_text_atomic(folder / name, text)
        written.append(folder / name)
    return written


def heat_map(
    values: npt.ArrayLike, mask: npt.ArrayLike, context: npt.ArrayLike
) -> npt.NDArray[np.float64]:
    """Colour ``values`` in [0, 1] with magma inside ``mask``, grey ``context`` outside.

    Parameters
    ----------
    values
        (h, w) float, clamped to [0, 1].
    mask
        (h, w) bool.
    context
        (h, w) float grey level in [0, 1] shown outside the mask.

    Returns
    -------
    (h, w, 3) float64
        Display RGB in [0, 1].
    """
    grey = np.repeat(np.asarray(context, dtype=np.float64)[..., None], 3, axis=-1)
    return np.where(np.asarray(mask, dtype=bool)[..., None], magma(values), grey)


def format_table(comparison: Comparison) -> str:
    """The comparison as Markdown: a header, the table, the reason for any dagger, the notes."""
    w, h = comparison.size
    az, el, dist = comparison.camera
    display = comparison.display
    lines = [
        f"# envstudio compare: {comparison.scene}, {w}x{h}",
        "",
        f"camera azimuth {az:g}°, elevation {el:g}°, distance {dist:g}; display exposure "
        f"{display['exposure']:g} EV, tone map {display['tonemap']}; "
        f"{int(comparison.mask.sum())} reflector pixels; {comparison.device}",
        "",
        f"methods: {_ssaa_text(comparison.ssaa)}",
        "",
        f"reference: {_reference_line(comparison)}",
        "",
        *(
            f"reference ({model}): {_run_line(run)}\n"
            for model, run in list(_references(comparison).items())[1:]
        ),
        *(
            f"reference ({model}, untraced): {_run_line(run)}\n"
            for model, run in comparison.untraced.items()
        ),
        "| method | PSNR (dB) | SSIM | FLIP | approximation error | scene error | scene only | "
        "ms/frame | reliable | reference | matched parameters |",
        "|:--|--:|--:|--:|--:|--:|--:|--:|:--|:--|:--|",
    ]
    for result in comparison.results:
        m = result.metrics
        mark = "" if result.reliable else UNRELIABLE
        lines.append(
            f"| {result.name} | {_psnr_text(m.psnr_db)}{mark} | {_fixed(m.ssim)}{mark} | "
            f"{_fixed(m.flip)}{mark} | {_percent_or_dash(result.approximation_error)} | "
            f"{_percent_or_dash(result.median_relative_error)} | "
            f"{_percent_or_dash(result.scene_only_error)} | {result.frame_ms['median_ms']:.2f} | "
            f"{'yes' if result.reliable else 'no'} | {_model_text(result)} | "
            f"{_matched_text(result)} |"
        )
    lines.append("")
    if not comparison.reliable:
        lines += [f"{UNRELIABLE} unreliable: {comparison.unreliable_reason}.", ""]
    lines += [
        f"Metrics on the {METRIC_NOTES['domain']}. PSNR: {METRIC_NOTES['psnr_db']}; SSIM: "
        f"{METRIC_NOTES['ssim']}; FLIP: {METRIC_NOTES['flip']}.",
        f"Errors: {METRIC_NOTES['errors']}",
        "ms/frame: wall clock with a GL finish at both ends; "
        + "; ".join(sorted({f"{r.name}: {r.timing}" for r in comparison.results})),
    ]
    for name, sections in comparison.extras.items():
        for extra in sections:
            lines += ["", *_extra_markdown(name, extra)]
    return "\n".join(lines)


def _extra_markdown(name: str, extra: ReportExtra) -> list[str]:
    """A method's report section as Markdown lines: heading, text, table, image links."""
    lines = [f"## {name}: {extra.title}", "", extra.text]
    if extra.columns:
        lines += [
            "",
            f"| {' | '.join(extra.columns)} |",
            "|:--|" + "--:|" * (len(extra.columns) - 1),
            *(f"| {' | '.join(row)} |" for row in extra.rows),
        ]
    for file, caption in extra.images:
        lines += ["", f"![{caption}]({file})"]
    return lines


def to_json(comparison: Comparison) -> dict:
    """The comparison as a JSON-ready dict (module docstring)."""
    ref = comparison.reference
    az, el, dist = comparison.camera
    return {
        "scene": comparison.scene,
        "size": list(comparison.size),
        "camera": {"azimuth": az, "elevation": el, "distance": dist},
        "display": comparison.display,
        "device": comparison.device,
        "ssaa": comparison.ssaa,
        "mask_pixels": int(comparison.mask.sum()),
        "reliable": comparison.reliable,
        "unreliable_reason": comparison.unreliable_reason,
        "metrics": METRIC_NOTES,
        "reference": {
            "parameters": ref.parameters,
            "samples": ref.status.samples,
            "batches": ref.status.batches,
            "rms_change": ref.status.rms_change,
            "converged": ref.status.converged,
            "stopping_rule": ref.stopping_rule,
            "stopped_by": ref.stopped_by,
            "frames": len(ref.frames_ms),
            "total_s": ref.total_s,
            "wall_s": ref.wall_s,
            "relative_standard_error": _number(ref.relative_standard_error),
            "resumed_samples": ref.resumed_samples,
            "exact_error": _exact_json(ref),
            "files": {"exr": "reference.exr", "png": "reference.png"},
        },
        "references": {
            model: {
                "model": run.parameters.get("model"),
                "parameters": run.parameters,
                "samples": run.status.samples,
                "converged": run.status.converged,
                "relative_standard_error": _number(run.relative_standard_error),
                "exact_error": _exact_json(run),
                "files": _reference_files(comparison, model),
            }
            for model, run in _references(comparison).items()
        },
        "untraced_references": {
            model: {
                "parameters": run.parameters,
                "samples": run.status.samples,
                "converged": run.status.converged,
                "wall_s": run.wall_s,
                "relative_standard_error": _number(run.relative_standard_error),
                "exact_error": _exact_json(run),
            }
            for model, run in comparison.untraced.items()
        },
        "methods": {
            r.name: {
                "parameters": r.parameters,
                "matched": r.matched,
                "glossiness": r.glossiness,
                "psnr_db": _number(r.metrics.psnr_db),
                "ssim": _number(r.metrics.ssim),
                "flip": _number(r.metrics.flip),
                "reference_model": r.reference_model,
                "reliable": r.reliable,
                "missing_input": r.missing_input,
                "median_relative_error": _number(r.median_relative_error),
                "scene_error": _number(r.median_relative_error),
                "approximation": None
                if r.approximation is None
                else {
                    "psnr_db": _number(r.approximation.psnr_db),
                    "ssim": _number(r.approximation.ssim),
                    "flip": _number(r.approximation.flip),
                    "median_relative_error": _number(r.approximation_error),
                },
                "scene_only_error": _number(r.scene_only_error),
                "frame_ms": r.frame_ms,
                "timing": r.timing,
                "files": _files(r.name),
                **(
                    {"extras": [e.to_json() for e in comparison.extras[r.name]]}
                    if r.name in comparison.extras
                    else {}
                ),
            }
            for r in comparison.results
        },
    }


def to_html(comparison: Comparison) -> str:
    """A self-contained page: the table, then per method a row of reference, frame, heat maps."""
    esc = html.escape
    table = _html_table(comparison)
    gradient = ", ".join(
        f"rgb({', '.join(str(round(255 * c)) for c in stop)})" for stop in MAGMA_STOPS
    )
    rows = []
    for r in comparison.results:
        files = _files(r.name)
        model = r.reference_model if r.reference_model in comparison.references else ""
        reference_png = _reference_files(comparison, model or next(iter(_references(comparison))))
        rows.append(
            _card(f"reference {model}".strip(), reference_png["png"], "")
            + _card(r.name, files["png"], f"PSNR {_psnr_text(r.metrics.psnr_db)} dB")
            + _card(f"{r.name}: FLIP", files["flip"], f"mean {_fixed(r.metrics.flip)}")
            + _card(f"{r.name}: relative error", files["relerr"], f"scale 0–{HEAT_SCALE:g}")
        )
    warning = (
        ""
        if comparison.reliable
        else f'<p class="warn">{UNRELIABLE} unreliable: {esc(comparison.unreliable_reason)}.</p>'
    )
    w, h = comparison.size
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>envstudio compare: {esc(comparison.scene)}</title>
<style>
body {{ font: 14px system-ui, sans-serif; margin: 1.5em; background: #1b1b1b; color: #ddd; }}
table {{ border-collapse: collapse; margin: 1em 0; }}
th, td {{ padding: 0.3em 0.8em; border-bottom: 1px solid #444; }}
td.n {{ text-align: right; font-variant-numeric: tabular-nums; }}
.warn {{ color: #ffb454; }}
.row {{ display: flex; flex-wrap: wrap; gap: 1em; margin-bottom: 1em; }}
figure {{ margin: 0; }}
figure img {{ width: {max(w, 256)}px; image-rendering: pixelated; display: block; }}
figure img.extra {{ width: auto; image-rendering: auto; }}
figcaption {{ font-size: 12px; color: #aaa; }}
.legend {{ display: flex; align-items: center; gap: 0.5em; margin-bottom: 1em; }}
.scale {{ width: 256px; height: 12px; background: linear-gradient(to right, {gradient}); }}
</style>
</head>
<body>
<h1>{esc(comparison.scene)}, {w}×{h}</h1>
<p>reference: {esc(_reference_line(comparison))}</p>
{table}
{warning}
<p>Metrics on the {esc(METRIC_NOTES["domain"])}. Errors: {esc(METRIC_NOTES["errors"])}.
Heat maps: FLIP error over [0, 1];
relative luminance error of the linear frames over [0, {HEAT_SCALE:g}]; grey: not measured.</p>
<div class="legend"><span>0</span><div class="scale"></div><span>top of scale</span></div>
{"".join(f'<div class="row">{row}</div>' for row in rows)}
{_html_extras(comparison)}
</body>
</html>
"""


def _html_table(comparison: Comparison) -> str:
    rows = []
    for r in comparison.results:
        m = r.metrics
        mark = "" if r.reliable else UNRELIABLE
        cells = [
            f"<td>{html.escape(r.name)}</td>",
            f'<td class="n">{_psnr_text(m.psnr_db)}{mark}</td>',
            f'<td class="n">{_fixed(m.ssim)}{mark}</td>',
            f'<td class="n">{_fixed(m.flip)}{mark}</td>',
            f'<td class="n">{_percent_or_dash(r.approximation_error)}</td>',
            f'<td class="n">{_percent_or_dash(r.median_relative_error)}</td>',
            f'<td class="n">{_percent_or_dash(r.scene_only_error)}</td>',
            f'<td class="n">{r.frame_ms["median_ms"]:.2f}</td>',
            f"<td>{'yes' if r.reliable else 'no'}</td>",
            f"<td>{html.escape(_model_text(r))}</td>",
            f"<td>{html.escape(_matched_text(r))}</td>",
        ]
        rows.append(f"<tr>{''.join(cells)}</tr>")
    head = "".join(
        f"<th>{c}</th>"
        for c in (
            "method",
            "PSNR (dB)",
            "SSIM",
            "FLIP",
            "approximation error",
            "scene error",
            "scene only",
            "ms/frame",
            "reliable",
            "reference",
            "matched",
        )
    )
    return f"<table><tr>{head}</tr>{''.join(rows)}</table>"


def _html_extras(comparison: Comparison) -> str:
    """The methods' report sections: a heading, the text, the table, the images."""
    esc = html.escape
    parts = []
    for name, sections in comparison.extras.items():
        for extra in sections:
            parts.append(f"<h2>{esc(name)}: {esc(extra.title)}</h2>\n<p>{esc(extra.text)}</p>")
            if extra.columns:
                head = "".join(f"<th>{esc(c)}</th>" for c in extra.columns)
                body = "".join(
                    "<tr>"
                    + "".join(
                        f"<td>{esc(c)}</td>" if k == 0 else f'<td class="n">{esc(c)}</td>'
                        for k, c in enumerate(row)
                    )
                    + "</tr>"
                    for row in extra.rows
                )
                parts.append(f"<table><tr>{head}</tr>{body}</table>")
            if extra.images:
                cards = "".join(_extra_image(file, caption) for file, caption in extra.images)
                parts.append(f'<div class="row">{cards}</div>')
    return "\n".join(parts)


def _extra_image(image: str, caption: str) -> str:
    """An image of a method's section at its own size (not the frames' width)."""
    esc = html.escape
    return (
        f'<figure><img class="extra" src="{esc(image)}" alt="{esc(caption)}">'
        f"<figcaption>{esc(caption)}</figcaption></figure>"
    )


def _card(title: str, image: str, caption: str) -> str:
    esc = html.escape
    return (
        f'<figure><img src="{esc(image)}" alt="{esc(title)}">'
        f"<figcaption>{esc(title)}{' — ' + esc(caption) if caption else ''}</figcaption></figure>"
    )


def _reference_line(comparison: Comparison) -> str:
    """The first reference: samples and time, stopping rule, noise, half-change."""
    return _run_line(comparison.reference)


def _run_line(ref: ReferenceRun) -> str:
    """Samples and time, the stopping rule and what stopped it, the noise, the half-change;
    for an exact run, its time and its checked error."""
    if ref.control_variate:
        return (
            f"control variate: traced, less β × (its untraced estimate − the exact one), "
            f"{ref.status.samples} spp in {len(ref.frames_ms)} frames ({ref.total_s:.1f} s); "
            f"stopping rule: {_rule_text(ref.stopping_rule)}; stopped: "
            f"{STOPPED_BY[ref.stopped_by]}; noise (median relative standard error) "
            f"{_percent(ref.relative_standard_error)}"
        )
    if ref.exact_error is not None:
        checked = ref.exact_error
        return (
            f"exact: the untraced model's integrals at the methods' samples in "
            f"{ref.total_s:.2f} s; against the brute force at {checked.describe()}: "
            f"median {_percent(checked.median)}, largest {_percent(checked.largest)}"
        )
    change = ref.status.rms_change
    state = "converged" if ref.converged else "NOT converged"
    half = "no half-change yet" if change is None else f"half-change {100 * change:.3g} %"
    limit = float(ref.parameters.get("time_limit", 0.0))
    budget = f"budget {ref.parameters['max_samples']} spp" + (
        f", time limit {limit:g} s" if limit > 0 else ""
    )
    return (
        f"{ref.status.samples} spp in {len(ref.frames_ms)} frames ({ref.total_s:.1f} s); "
        f"stopping rule: {_rule_text(ref.stopping_rule)}; stopped: {STOPPED_BY[ref.stopped_by]}; "
        f"noise (median relative standard error) {_percent(ref.relative_standard_error)}; {half} "
        f"(tolerance {100 * float(ref.parameters['tolerance']):.3g} %, {budget}): {state}"
    )


def _ssaa_text(ssaa: int) -> str:
    """How the methods' pixels were sampled, beside the reference's footprint average."""
    if ssaa == 1:
        return "one sample at each pixel's centre (the reference averages the footprint)"
    return (
        f"{ssaa}×{ssaa} samples per pixel, box-filtered, as the reference averages each "
        "pixel's footprint (ms/frame at one sample per pixel)"
    )


def _rule_text(rule: str) -> str:
    if rule == NOISE_RULE:
        return f"noise < {NOISE_SHARE:g} × each method's median relative error (default)"
    return "half-change < tolerance (strict)"


def _percent_or_dash(value: float) -> str:
    return "–" if not np.isfinite(value) else f"{100 * value:.2f} %"


def _percent(value: float) -> str:
    return f"{100 * value:.3g} %" if math.isfinite(value) else "—"


def _matched_text(result: MethodResult) -> str:
    text = ", ".join(f"{k}={_value_text(v)}" for k, v in result.matched.items()) or "none"
    return f"{text} ({result.glossiness})" if result.glossiness else text


def _value_text(value: object) -> str:
    """A number as ``%g``, a colour as ``--param`` takes it (``1,0.71,0.29``; a grey ``0.5``)."""
    if isinstance(value, (tuple, list)) and value and all(isinstance(c, float) for c in value):
        return _value_text(value[0]) if len(set(value)) == 1 else ",".join(f"{c:g}" for c in value)
    return f"{value:g}" if isinstance(value, float) else str(value)


def _psnr_text(value: float) -> str:
    if math.isnan(value):
        return "—"
    return "∞" if math.isinf(value) else f"{value:.2f}"


def _fixed(value: float) -> str:
    """A metric to four places, or a dash for none."""
    return "—" if math.isnan(value) else f"{value:.4f}"


def _model_text(result: MethodResult) -> str:
    """The reference a row was measured against, or why it has no numbers."""
    return result.reference_model or "no ground truth for this model"


def _exact_json(run: ReferenceRun) -> dict[str, float] | None:
    """An exact run's checked error against the brute force (None: a Monte Carlo run)."""
    return None if run.exact_error is None else asdict(run.exact_error)


def _references(comparison: Comparison) -> dict[str, ReferenceRun]:
    """Model → reference run, the first being ``comparison.reference``."""
    return comparison.references or {"": comparison.reference}


def _reference_files(comparison: Comparison, model: str) -> dict[str, str]:
    """``reference.exr``/``.png`` for the first reference, ``reference-<model>.*`` for others."""
    first = next(iter(_references(comparison)))
    stem = "reference" if model == first else f"reference-{model}"
    return {"exr": f"{stem}.exr", "png": f"{stem}.png"}


def _number(value: float) -> float | str | None:
    """A float, ``"inf"`` for +infinity, None for no number (JSON has neither)."""
    if math.isnan(value):
        return None
    return "inf" if math.isinf(value) else value


def _files(name: str) -> dict[str, str]:
    return {
        "exr": f"{name}.exr",
        "png": f"{name}.png",
        "flip": f"{name}.flip.png",
        "relerr": f"{name}.relerr.png",
    }
