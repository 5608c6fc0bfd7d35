"""Log every judgement of the reference's stopping rule while a command runs.

    python studies/exact-reference/judgements.py LOG.jsonl atlas --envs sunrise --meshes knot \
        --exponents 100 --time-limit 60 --out DIR

Runs ``envstudio`` with the given arguments; each time the rule judges the methods against
the reference (measure/stopping.ReferenceJudge.judge), one JSON line goes to LOG.jsonl: the
model, samples per pixel, seconds, the noise, each method's median error and uncertainty, and
how many pixels of the mask trace something. ``python judgements.py LOG.jsonl`` alone prints,
per model, each judgement's errors as a share of the last judgement's.
"""

from __future__ import annotations

import json
import sys

import numpy as np


def log_judgements(path: str) -> None:
    """Wrap ReferenceJudge.judge so that each judgement is appended to ``path``."""
    from envstudio.measure import stopping

    judge = stopping.ReferenceJudge.judge
    log = open(path, "a")  # kept open while the command runs

    def logged(self, reference, hdr, mask, *args):
        judgement = judge(self, reference, hdr, mask, *args)
        pixel_noise = args[1] if len(args) > 1 else None
        traced = -1 if pixel_noise is None else int((pixel_noise > 0)[mask].sum())
        record = {
            "model": reference.values["model"],
            "spp": judgement.samples,
            "seconds": judgement.seconds,
            "noise": judgement.noise,
            "errors": judgement.errors,
            "uncertainties": judgement.uncertainties,
            "traced": traced,
            "mask": int(mask.sum()),
        }
        log.write(json.dumps(record) + "\n")
        log.flush()
        return judgement

    stopping.ReferenceJudge.judge = logged


def summarise(path: str) -> None:
    """Per model: each judgement's errors as a share of the last's, and the traced pixels."""
    rows = [json.loads(line) for line in open(path)]
    for model in dict.fromkeys(r["model"] for r in rows):
        runs = [r for r in rows if r["model"] == model]
        last = runs[-1]["errors"]
        print(f"{model}: last at {runs[-1]['spp']} spp")
        for r in runs:
            off = {k: f"{100 * (r['errors'][k] - v) / v:+.1f} %" for k, v in last.items() if v}
            spread = r["uncertainties"] or {}
            share = {
                k: f"{100 * u / r['errors'][k]:.1f} %" for k, u in spread.items() if np.isfinite(u)
            }
            print(
                f"  {r['spp']:5d} spp traced {r['traced']:5d}/{r['mask']}: off {off}; "
                f"uncertainty/error {share}"
            )


if __name__ == "__main__":
    if len(sys.argv) == 2:
        summarise(sys.argv[1])
    else:
        log_judgements(sys.argv[1])
        from envstudio.cli import main

        sys.exit(main(sys.argv[2:]))
