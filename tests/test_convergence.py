"""``bench --converge``: the reference timed to its tolerance, and the projection past a limit."""

import os
import signal
import threading
import time

import numpy as np
import pytest

from envstudio.methods.reference import project_convergence
from envstudio.render.convergence import format_convergence, run_convergence
from envstudio.render.session import RenderSession
from envstudio.scene.environment import Environment
from test_reference_gl import smooth_environment
from test_render_gl import sphere_scene


def test_projection_recovers_a_power_law():
    # change = 0.5 / sqrt(n), 2 ms per sample: 0.1 % at n = 250 000, 500 s
    checks = [
        {"samples": n, "change": 0.5 / np.sqrt(n), "seconds": 0.002 * n}
        for n in (64, 128, 256, 512, 1024)
    ]
    projection = project_convergence(checks, 0.001)
    assert projection["slope"] == pytest.approx(-0.5, abs=1e-9)
    assert projection["samples"] == pytest.approx(250_000, rel=1e-6)
    assert projection["seconds"] == pytest.approx(500, rel=1e-6)


def test_no_projection_from_one_check_or_a_flat_change():
    assert project_convergence([{"samples": 64, "change": 0.1, "seconds": 1.0}], 0.001) is None
    flat = [{"samples": n, "change": 0.05, "seconds": n / 100} for n in (64, 128, 256)]
    assert project_convergence(flat, 0.001) is None


def test_reference_converges_on_a_sphere_and_records_each_doubling(gl_ctx):
    session = RenderSession(sphere_scene(Environment(smooth_environment()), rings=64), ctx=gl_ctx)
    method = session.method("reference")
    method.values.update({"trace": False, "kd": 0.8, "fresnel": 0.2, "phong_exponent": 30.0})
    method.values.update({"tolerance": 0.01, "samples": 4, "adaptive": False})
    report = run_convergence(session, method, (32, 32), time_limit_s=120.0, progress=False)
    assert report["converged"], report["checks"]
    samples = [c["samples"] for c in report["checks"]]
    assert samples == [16 * 2**k for k in range(len(samples))], "one check per doubling of batches"
    assert report["checks"][-1]["change"] < 0.01 <= report["checks"][-2]["change"]
    assert report["samples"] == samples[-1]
    assert "converged: " in format_convergence(report)
    session.release()


def test_a_time_limit_stops_short_and_projects(gl_ctx):
    session = RenderSession(sphere_scene(Environment(smooth_environment()), rings=64), ctx=gl_ctx)
    method = session.method("reference")
    # a budget no machine spends in 3 s: the time limit is what stops it
    method.values.update({"trace": False, "tolerance": 1e-5, "samples": 4})
    method.values["max_samples"] = 10_000_000
    report = run_convergence(session, method, (32, 32), time_limit_s=3.0, progress=False)
    assert not report["converged"]
    assert report["projection"]["samples"] > report["samples"]
    assert report["projection"]["seconds"] > report["checks"][-1]["seconds"]
    assert "NOT converged" in format_convergence(report)
    # the viewer's and the CLI's status line says how long is left
    assert method.status_line().endswith(" to go"), method.status_line()
    session.release()


@pytest.mark.parametrize("adaptive", [False, True])
def test_a_resumed_convergence_run_continues_the_checks_and_the_estimate(gl_ctx, adaptive):
    def run(max_samples: int, resume: bool):
        session = RenderSession(
            sphere_scene(Environment(smooth_environment()), rings=64), ctx=gl_ctx
        )
        method = session.method("reference")
        method.values.update({"trace": False, "tolerance": 1e-5, "samples": 4})
        method.values["adaptive"] = adaptive
        method.values["max_samples"] = max_samples
        report = run_convergence(session, method, (32, 32), 120.0, progress=False, resume=resume)
        estimate = method.estimate()
        session.release()
        return report, estimate

    first, _ = run(64, resume=True)
    resumed, estimate = run(256, resume=True)
    whole, expected = run(256, resume=False)
    assert first["resumed_samples"] == 0 and resumed["resumed_samples"] == first["samples"]
    assert first["samples"] == 64 or adaptive  # adaptive: the mean over pixels passes 64
    # the doublings of the first run are kept, with their times, and the sequence continues
    assert resumed["checks"][: len(first["checks"])] == first["checks"]
    assert [c["samples"] for c in resumed["checks"]] == [c["samples"] for c in whole["checks"]]
    assert resumed["checks"][-1]["change"] == pytest.approx(whole["checks"][-1]["change"], rel=1e-4)
    assert resumed["seconds"] >= first["seconds"] + resumed["run_seconds"] * 0.99
    np.testing.assert_allclose(estimate, expected, rtol=1e-5, atol=1e-6)
    assert f"resumed at {first['samples']} spp" in format_convergence(resumed)


def test_an_interrupted_run_saves_its_accumulation_and_the_next_one_resumes_it(gl_ctx):
    def session_and_method():
        session = RenderSession(
            sphere_scene(Environment(smooth_environment()), rings=64), ctx=gl_ctx
        )
        method = session.method("reference")
        method.values.update({"trace": False, "tolerance": 1e-5, "samples": 4})
        method.values["max_samples"] = 10_000_000
        return session, method

    session, method = session_and_method()

    def interrupt_after_three_batches():
        while method.status.batches < 3:
            time.sleep(0.01)
        os.kill(os.getpid(), signal.SIGINT)  # a real Ctrl-C, mid-run

    thread = threading.Thread(target=interrupt_after_three_batches)
    thread.start()
    with pytest.raises(KeyboardInterrupt):
        run_convergence(session, method, (32, 32), 600.0, progress=False, resume=True)
    thread.join()
    interrupted_at = method.status.batches
    expected = method.estimate()
    session.release()
    assert interrupted_at >= 3

    session, method = session_and_method()
    method.values["max_samples"] = 4 * interrupted_at  # resume, then stop at the same count
    report = run_convergence(session, method, (32, 32), 600.0, progress=False, resume=True)
    assert report["resumed_samples"] == 4 * interrupted_at
    assert method.status.batches == interrupted_at
    np.testing.assert_array_equal(method.estimate(), expected)
    session.release()
