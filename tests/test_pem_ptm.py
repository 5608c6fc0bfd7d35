"""The PTM of seed 003 Figure 7 (issue 31): a per-texel polynomial in the view parameters.

The bake infers a surface texture per view (model ``ptm``, looked up by the
surface point, methods/pem/bake/lookups.py); the playback sums the views of a
window with the weights of the least-squares polynomial's value at the camera
(methods/pem/blending.py ``ptm_blend``). At a sampled view the polynomial does
not pass through the map it was fitted to: it misses it by its fit residual,
and by no more.
"""

from pathlib import Path

import numpy as np
from numpy.polynomial import polynomial

from envstudio.engine.session import RenderSession
from envstudio.methods.pem.atlas import flat_maps
from envstudio.methods.pem.blending import ptm_blend
from envstudio.methods.pem.lookups_gl import GlLookups
from test_pem_playback_gl import LOD_BIAS, N, R, _fake_bake, room  # noqa: F401 (fixture)

VIEWS = 6


def _smooth_in_view(bake, seed=1):
    """PTM maps x_v = c0 + c1 v + c2 v² + noise_v per texel: a fit with a small residual."""
    rng = np.random.default_rng(seed)
    for k, level in enumerate(bake.maps["ptm"]):
        shape = level.shape[1:]
        c = [rng.uniform(0.3, 0.6, shape), rng.uniform(-0.05, 0.05, shape)]
        c.append(rng.uniform(-0.01, 0.01, shape))
        v = np.arange(VIEWS, dtype=np.float64).reshape(-1, *([1] * len(shape)))
        noise = rng.normal(0.0, 0.01, level.shape)
        bake.maps["ptm"][k] = (c[0] + c[1] * v + c[2] * v**2 + noise).astype(np.float32)


def _eye(bake, view):
    space = bake.view_space
    a, e = np.radians(space["azimuths"][view]), np.radians(space["elevations"][0])
    offset = np.array([np.sin(a) * np.cos(e), np.sin(e), np.cos(a) * np.cos(e)])
    return np.asarray(space["target"]) + space["distance"] * offset


def test_ptm_weights_are_the_least_squares_polynomial():
    space = {"kind": "arc", "azimuths": [25.0 + 2 * k for k in range(VIEWS)], "elevations": [20.0]}
    space.update(target=[0.0, 0.0, 0.0], distance=1.0)
    values = np.random.default_rng(0).normal(size=(VIEWS, 50))
    for view in range(VIEWS):
        for shift in (0.0, 0.3, 0.5):
            at = min(view + shift, VIEWS - 1)
            az = np.radians(25.0 + 2 * at)
            eye = [np.sin(az) * np.cos(np.radians(20)), np.sin(np.radians(20)), 0.0]
            eye[2] = np.cos(az) * np.cos(np.radians(20))
            blend = ptm_blend(space, eye)
            idx = np.array(blend.views)
            fit = polynomial.polyfit(idx.astype(float), values[idx], 2)
            want = polynomial.polyval(at, fit)
            got = np.asarray(blend.weights) @ values[idx]
            np.testing.assert_allclose(got, want, atol=1e-9)
            assert abs(sum(blend.weights) - 1.0) < 1e-9 and len(idx) in (3, 4)


def test_ptm_at_a_sample_view_reproduces_its_map_within_the_fit_residual(gl_ctx, room):  # noqa: F811
    scene, box, ellipsoids = room
    bake = _fake_bake(scene, box, ellipsoids, views=VIEWS)
    _smooth_in_view(bake)
    session = RenderSession(scene, ctx=gl_ctx, cube_size=32)
    method = session.method("pem")
    method.show(bake, session.gpu_scene, Path("fake.pem"))
    method.values.update({"snap": True, "kd": 0.0, "fresnel_layer": False, "em_model": "ptm"})
    session.renderer.display["background"] = False
    lookups = GlLookups(scene, ctx=gl_ctx)
    flat = flat_maps(bake.maps["ptm"]).reshape(VIEWS, len(bake.parts), -1, 4)[..., :3]
    checked = 0
    for view in (1, 2, 3):  # inner views: four maps in the window, so a residual
        method.values["path"] = view / (VIEWS - 1)
        session.render_offscreen(method, (R, R))
        got = session.read_hdr()[..., :3].astype(np.float64).reshape(-1, 3)
        blend = method.last_blend
        assert blend.views == ptm_blend(bake.view_space, _eye(bake, view)).views
        assert len(blend.views) == 4
        idx = np.array(blend.views)
        # the per-texel polynomial, fitted independently, and its residual at the view
        coeffs = polynomial.polyfit(idx.astype(float), flat[idx].reshape(len(idx), -1), 2)
        fitted = polynomial.polyval(float(view), coeffs).reshape(flat.shape[1:])
        residual = fitted - flat[view]
        assert np.abs(residual).max() > 1e-3  # a real fit, not an interpolation
        found = lookups.render(session.camera, R, N, bake.box, bake.origins, bake.ellipsoids)
        for p in range(len(bake.parts)):
            on = found.part.ravel() == p
            a = found.matrix("ptm", p, lod_bias=LOD_BIAS)
            np.testing.assert_allclose(got[on], (a @ fitted[p])[on], atol=2e-4)
            miss = np.abs(got[on] - (a @ flat[view, p])[on])
            bound = np.abs(a @ residual[p])[on] + 2e-4
            assert (miss <= bound).all()
            checked += int(on.sum())
    assert checked > 600
    lookups.release()
    session.release()


def _grid_eye(azimuth, elevation):
    a, e = np.radians(azimuth), np.radians(elevation)
    return [np.sin(a) * np.cos(e), np.sin(e), np.cos(a) * np.cos(e)]


def _biquadratic(c, azimuth, elevation):
    """c[0] + c[1] a + c[2] e + c[3] a² + c[4] a e + c[5] e² in 5°-step units."""
    a, e = azimuth / 5.0, elevation / 5.0
    return c[0] + c[1] * a + c[2] * e + c[3] * a * a + c[4] * a * e + c[5] * e * e


def test_a_closed_orbits_ptm_window_wraps_and_drops_views_that_saw_nothing():
    """On a full orbit the 4 × 4 window crosses 360° (azimuths unwrapped about the camera),
    and views that saw no reflector leave the fit: the weights still give any biquadratic's
    value at the camera, exactly, from the views kept (seed 003 Figure 7's polynomial)."""
    azimuths, elevations = [5.0 * k for k in range(72)], [-10.0, -5.0, 0.0, 5.0, 10.0]
    space = {"kind": "grid", "closed": True, "azimuths": azimuths, "elevations": elevations}
    space.update(target=[0.0, 0.0, 0.0], distance=1.0)
    coefficients = np.random.default_rng(3).normal(size=(6, 20))
    below = set(range(72))  # the row at −10° saw nothing (a camera under the floor)
    for azimuth, elevation in ((357.5, 2.5), (1.0, -4.0), (183.0, 7.0), (359.0, -6.0)):
        eye = _grid_eye(azimuth, elevation)
        for usable in (None, lambda v: v not in below):
            blend = ptm_blend(space, eye, usable=usable)
            views = np.array(blend.views)
            near = azimuth - 360.0 * (azimuth > 180.0)  # the window's azimuths about the camera
            a = np.array([azimuths[v % 72] for v in views])
            a = a - 360.0 * (a - near > 180.0)
            e = np.array([elevations[v // 72] for v in views])
            c = coefficients.copy()
            c[5] *= len(set(e)) > 2  # two rows kept do not determine e² (the degree is cut)
            got = np.asarray(blend.weights) @ _biquadratic(c, a[:, None], e[:, None])
            want = _biquadratic(c, near, elevation)
            np.testing.assert_allclose(got, want, atol=1e-9)
            assert len({v % 72 for v in views.tolist()}) == 4 and np.abs(a - near).max() < 10.0
            if usable is not None:
                assert not below & set(views.tolist())
    # only two rows left: the degree in e is cut to 1, still exact for what they determine
    blend = ptm_blend(space, _grid_eye(90.0, -7.5), usable=lambda v: v // 72 in (1, 2))
    e = np.array([elevations[v // 72] for v in blend.views])
    assert set(e) == {-5.0, 0.0} and abs(np.asarray(blend.weights) @ e - -7.5) < 1e-9
