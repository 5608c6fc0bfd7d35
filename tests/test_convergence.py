"""``bench --converge``: the reference timed to its tolerance, and the projection past a limit."""

import os
import signal
import threading
import time

import numpy as np
import pytest

from envstudio.engine.session import RenderSession
from envstudio.measure.convergence import format_convergence, run_convergence
from envstudio.plugin import is_checkpoint, project_convergence
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


def test_checkpoints_are_four_per_doubling_and_hold_their_halves():
    points = [b for b in range(1, 97) if is_checkpoint(b)]
    assert points == [2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16, 20, 24, 28, 32, 40, 48, 56, 64, 80, 96]
    assert points[-1] == 96 and [b for b in range(97, 129) if is_checkpoint(b)] == [112, 128]
    assert all(b // 2 in points for b in points if b % 2 == 0 and b > 2)


def test_a_check_between_doublings_is_the_change_since_half_the_batches(gl_ctx):
    session = RenderSession(sphere_scene(Environment(smooth_environment()), rings=64), ctx=gl_ctx)
    method = session.method("reference")
    method.values.update({"trace": False, "tolerance": 1e-5, "samples": 4, "adaptive": False})
    session.renderer.display["background"] = False
    estimates = {}
    for batches in range(1, 13):
        session.render_offscreen(method, (32, 32))
        estimates[batches] = method.estimate().astype(np.float64)
    mask = method.coverage()
    expected = [
        np.sqrt(np.mean((estimates[b][mask] - estimates[b // 2][mask]) ** 2))
        / np.sqrt(np.mean(estimates[b][mask] ** 2))
        for b in (4, 6, 8, 10, 12)
    ]
    assert [c["samples"] for c in method.status.checks] == [16, 24, 32, 40, 48]
    changes = [c["change"] for c in method.status.checks]
    np.testing.assert_allclose(changes, expected, rtol=1e-6)
    session.release()


def test_reference_converges_on_a_sphere_and_records_each_check(gl_ctx):
    session = RenderSession(sphere_scene(Environment(smooth_environment()), rings=64), ctx=gl_ctx)
    method = session.method("reference")
    method.values.update({"trace": False, "kd": 0.8, "fresnel": 0.2, "phong_exponent": 30.0})
    method.values.update({"tolerance": 0.01, "samples": 4, "adaptive": False})
    report = run_convergence(session, method, (32, 32), time_limit_s=120.0, progress=False)
    assert report["converged"], report["checks"]
    samples = [c["samples"] for c in report["checks"]]
    batches = [b for b in range(4, 10_000, 2) if is_checkpoint(b) and is_checkpoint(b // 2)]
    assert samples == [4 * b for b in batches[: len(samples)]], "four checks per doubling"
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


def test_a_larger_budget_or_another_tolerance_continues_the_accumulation(gl_ctx):
    def sphere():
        session = RenderSession(
            sphere_scene(Environment(smooth_environment()), rings=64), ctx=gl_ctx
        )
        session.renderer.display["background"] = False
        method = session.method("reference")
        method.values.update({"trace": False, "samples": 16, "tolerance": 1e-5})
        return session, method

    session, method = sphere()
    method.values["max_samples"] = 64
    while not method.finished():
        session.render_offscreen(method, (32, 32))
    assert method.status.batches == 4 and "budget spent" in method.status_line()
    method.values["max_samples"] = 10_000
    method.values["samples_per_draw"] = 3  # six draws per batch from here on, one short
    session.render_offscreen(method, (32, 32))
    assert method.status.batches == 5, "the larger budget restarted the accumulation"
    # the last check (4 batches against 2) is judged again under each tolerance at once
    change = method.status.rms_change
    method.values["tolerance"] = 2 * change
    session.render_offscreen(method, (32, 32))
    assert method.status.converged and method.status.batches == 5
    method.values["tolerance"] = 1e-5
    session.render_offscreen(method, (32, 32))
    assert not method.status.converged and method.status.batches == 6
    continued = method.estimate()
    session.release()

    session, method = sphere()
    for _ in range(6):
        session.render_offscreen(method, (32, 32))
    np.testing.assert_allclose(continued, method.estimate(), rtol=1e-5, atol=1e-6)
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
    # both runs' seconds (less the first frame's set-up before the state is restored)
    assert resumed["seconds"] >= first["seconds"] + resumed["run_seconds"] - 0.5
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

    interrupted = threading.Event()

    def interrupt_after_three_batches():
        while method.status.batches < 3:
            time.sleep(0.01)
        # A real Ctrl-C, mid-run. Once in a full suite (session 7) the signal, sent from this
        # thread, never became a KeyboardInterrupt and the run went on to its time limit (SIGINT
        # ignored, below). Send it again while batches go on: an interrupted run draws no more.
        while not interrupted.is_set():
            sent_at = method.status.batches
            os.kill(os.getpid(), signal.SIGINT)
            while not interrupted.is_set() and method.status.batches < sent_at + 2:
                time.sleep(0.01)

    # A suite started in the background by a non-interactive shell inherits SIGINT ignored,
    # and Python then installs no handler: the Ctrl-C would be lost and the run go on to its
    # time limit. The terminal's Ctrl-C is what is tested, so its handler is put in place.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    thread = threading.Thread(target=interrupt_after_three_batches)
    thread.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            run_convergence(session, method, (32, 32), 600.0, progress=False, resume=True)
    finally:
        interrupted.set()
        thread.join()
        signal.signal(signal.SIGINT, previous)
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


def test_a_state_saved_with_one_snapshot_before_session_5_resumes_its_checks(gl_ctx):
    def render(batches: int, state=None):
        session = RenderSession(
            sphere_scene(Environment(smooth_environment()), rings=64), ctx=gl_ctx
        )
        method = session.method("reference")
        method.values.update({"trace": False, "tolerance": 1e-5, "samples": 4, "adaptive": False})
        session.renderer.display["background"] = False
        if state is not None:
            method.resume(state)
        for _ in range(batches):
            session.render_offscreen(method, (32, 32))
        return session, method

    session, method = render(12)
    state = method.accumulation_state()
    session.release()
    # the old format: only the estimate at the last doubling (8 batches)
    legacy = {k: v for k, v in state.items() if k not in ("snapshots", "snapshot_batches")}
    legacy["snapshot"] = state["snapshots"][list(state["snapshot_batches"]).index(8)]
    session, resumed = render(4, legacy)
    session.release()
    session, whole = render(16)
    session.release()
    # 14 needs 7, which the old state lacks; 16 compares with the saved 8
    assert [c["samples"] for c in resumed.status.checks][-2:] == [48, 64]
    assert [c["samples"] for c in whole.status.checks][-2:] == [56, 64]
    assert resumed.status.checks[-1]["change"] == pytest.approx(whole.status.checks[-1]["change"])
