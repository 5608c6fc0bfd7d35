"""``envstudio bench``: which methods it times, and that every time it reports is measured."""

import json

from envstudio.cli import main
from envstudio.engine.registry import available_methods


def test_bench_times_every_one_frame_method_unless_a_progressive_one_is_named(tmp_path):
    out = tmp_path / "bench.json"
    args = ["bench", "--size", "48x32", "--frames", "2", "--warmup", "1", "--json", str(out)]
    assert main(args) == 0
    report = json.loads(out.read_text())
    one_frame = [name for name, cls in available_methods().items() if not cls.progressive]
    assert "reference" in available_methods() and "reference" not in one_frame
    assert list(report["methods"]) == one_frame
    for name, timing in report["methods"].items():
        assert 0 < timing["frame"]["median_ms"] <= timing["frame"]["p95_ms"], name
    # named, the reference's frames are timed too: each is one batch of its accumulation
    assert main([*args[:-2], "--json", str(out), "--methods", "reference,mirror"]) == 0
    report = json.loads(out.read_text())
    assert list(report["methods"]) == ["reference", "mirror"]
    assert report["methods"]["reference"]["frame"]["median_ms"] > 0
