"""Issue 38 item 2: every report writer says why, whichever references are unreliable.

GL-free: comparisons are built from their dataclasses, with two or three references
(one per reflectance model), every combination of converged and not, and each writer
(Markdown, JSON, HTML, the files on disk) must name the reason of every reference that
left a method unreliable, and nothing when all are reliable.
"""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from envstudio.core.metrics import ImageMetrics
from envstudio.measure.compare import Comparison, MethodResult
from envstudio.measure.ground_truth import ConvergenceStatus
from envstudio.measure.reference_runs import ReferenceRun
from envstudio.measure.report import format_table, to_html, to_json, write_report

SIZE = (4, 3)
MODELS = ("phong", "banks", "microfacet")


def reference_run(converged: bool, seconds: float) -> ReferenceRun:
    """A reference that converged, or ran out of a ``seconds`` time limit."""
    h, w = SIZE[1], SIZE[0]
    return ReferenceRun(
        parameters={"time_limit": seconds, "max_samples": 64, "tolerance": 0.01},
        status=ConvergenceStatus(batches=4, samples=16, rms_change=0.05, converged=converged),
        frames_ms=[1.0, 1.0],
        total_s=seconds,
        relative_standard_error=0.02,
        resumed_samples=0,
        hdr=np.full((h, w, 3), 0.5, np.float32),
        display=np.full((h, w, 3), 0.5, np.float32),
        stopped_by="converged" if converged else "time_limit",
    )


def method_result(name: str, model: str, reliable: bool) -> MethodResult:
    h, w = SIZE[1], SIZE[0]
    return MethodResult(
        name=name,
        parameters={},
        matched={},
        glossiness=None,
        metrics=ImageMetrics(30.0, 0.9, 0.05, np.zeros((h, w), np.float32)),
        relative_error=np.zeros((h, w), np.float32),
        frame_ms={"median_ms": 1.0, "p95_ms": 1.0},
        timing="wall clock",
        hdr=np.full((h, w, 3), 0.5, np.float32),
        display=np.full((h, w, 3), 0.5, np.float32),
        median_relative_error=0.1,
        reliable=reliable,
        reference_model=model,
    )


def comparison(converged: tuple[bool, ...]) -> Comparison:
    """One method per model; reference ``i`` converged as ``converged[i]`` (its time limit
    is 10 + i s, so each reference's reason is told apart by its number)."""
    models = MODELS[: len(converged)]
    runs = {
        m: reference_run(ok, 10.0 + i)
        for i, (m, ok) in enumerate(zip(models, converged, strict=True))
    }
    results = [method_result(f"method-{m}", m, runs[m].converged) for m in models]
    return Comparison(
        scene="test",
        size=SIZE,
        camera=(0.0, 0.0, 3.0),
        display={"exposure": 0.0, "tonemap": "none"},
        device="none",
        mask=np.ones((SIZE[1], SIZE[0]), bool),
        reference=next(iter(runs.values())),
        results=results,
        references=runs,
    )


CASES = [c for n in (2, 3) for c in itertools.product((True, False), repeat=n)]


@pytest.mark.parametrize("converged", CASES, ids=lambda c: "".join("RU"[not x] for x in c))
def test_every_writer_names_the_reason_of_each_unreliable_reference(converged, tmp_path):
    subject = comparison(converged)
    unreliable = [f"{10 + i:g} s" for i, ok in enumerate(converged) if not ok]
    reliable = [f"{10 + i:g} s" for i, ok in enumerate(converged) if ok]

    markdown, page = format_table(subject), to_html(subject)
    document = to_json(subject)
    assert document["reliable"] == all(converged)
    written = write_report(subject, tmp_path / "report")
    assert {p.name for p in written} >= {"compare.md", "compare.json", "index.html"}
    on_disk = json.loads((tmp_path / "report" / "compare.json").read_text())
    assert on_disk["unreliable_reason"] == document["unreliable_reason"]
    if all(converged):
        assert document["unreliable_reason"] is None
        assert "unreliable:" not in markdown and "unreliable:" not in page
        return
    reason = document["unreliable_reason"]
    assert isinstance(reason, str) and "None" not in reason
    for text in (reason, markdown, page):
        for limit in unreliable:
            assert f"time limit of {limit}" in text
        for limit in reliable:
            assert f"time limit of {limit}" not in text
    for model, ok in zip(MODELS, converged, strict=False):
        assert (f"reference ({model}):" in reason) is not ok


def test_a_method_whose_model_has_no_reference_says_so():
    subject = comparison((True, True))
    subject.results.append(method_result("orphan", "unknown-model", reliable=False))
    assert subject.unreliable_reason == "orphan: no reference of its reflectance model"
    assert "orphan: no reference of its reflectance model" in to_html(subject)
