"""PEM playback's view blending (methods/pem/blending.py): continuous, weights summing to 1."""

import numpy as np

from envstudio.methods.pem.blending import camera_angles, view_blend


def _eye(azimuth, elevation, target=(0.0, 0.0, 0.0), distance=3.0):
    az, el = np.radians(azimuth), np.radians(elevation)
    offset = np.array([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)])
    return np.asarray(target) + distance * offset


def _image_weights(space, eye, blend=True):
    """Dense per-view weights of a camera: what the shader blends."""
    b = view_blend(space, eye, blend)
    dense = np.zeros(len(space["azimuths"]) * len(space["elevations"]))
    np.add.at(dense, list(b.views), b.weights)
    return dense


def test_camera_angles_invert_the_orbit_camera():
    for az, el in [(0, 0), (90, 10), (-135, -40), (179, 80)]:
        got = camera_angles(_eye(az, el, (1, 2, 3)), (1, 2, 3))
        assert np.allclose(got, (az, el), atol=1e-9)


def test_arc_weights_are_continuous_and_sum_to_one_past_both_ends():
    space = {
        "kind": "arc",
        "azimuths": [20.0, 21.0, 22.0, 23.0, 24.0],
        "elevations": [18.0],
        "target": [0.0, 0.0, 0.0],
    }
    sweep = np.linspace(10.0, 34.0, 2401)  # 0.01° steps, past both ends of an open arc
    dense = np.array([_image_weights(space, _eye(a, 18.0)) for a in sweep])
    assert np.allclose(dense.sum(axis=1), 1.0)
    assert (dense >= 0).all()
    # continuity: a 0.01° step moves the weights by at most 0.01 per view (slope 1 per degree)
    assert np.abs(np.diff(dense, axis=0)).max() <= 0.01 + 1e-9
    # at a sample the sample alone; midway an even split; beyond the ends the end view
    assert np.allclose(_image_weights(space, _eye(22.0, 18.0)), [0, 0, 1, 0, 0])
    assert np.allclose(_image_weights(space, _eye(21.5, 18.0)), [0, 0.5, 0.5, 0, 0])
    assert np.allclose(_image_weights(space, _eye(5.0, 18.0)), [1, 0, 0, 0, 0])
    assert np.allclose(_image_weights(space, _eye(40.0, 18.0)), [0, 0, 0, 0, 1])
    # an azimuth one turn away is the same camera
    assert np.allclose(_image_weights(space, _eye(21.3 - 360.0, 18.0)), dense[1130])
    # unblended: the nearest sample
    assert np.allclose(_image_weights(space, _eye(21.4, 18.0), blend=False), [0, 1, 0, 0, 0])
    assert np.allclose(_image_weights(space, _eye(21.6, 18.0), blend=False), [0, 0, 1, 0, 0])


def test_grid_weights_are_bilinear_continuous_and_sum_to_one():
    space = {
        "kind": "grid",
        "azimuths": [0.0, 10.0, 20.0],
        "elevations": [0.0, 15.0],
        "target": [0.0, 0.0, 0.0],
    }
    rng = np.random.default_rng(3)
    for az, el in zip(rng.uniform(-10, 30, 200), rng.uniform(-10, 25, 200), strict=True):
        w = _image_weights(space, _eye(az, el))
        assert np.isclose(w.sum(), 1.0) and (w >= 0).all()
    w = _image_weights(space, _eye(5.0, 7.5))  # centre of the first cell: four equal weights
    assert np.allclose(w, [0.25, 0.25, 0, 0.25, 0.25, 0])
    path = [_image_weights(space, _eye(a, 0.5 * a)) for a in np.linspace(-5, 25, 3001)]
    assert np.abs(np.diff(path, axis=0)).max() < 0.01


def test_a_closed_orbit_blends_across_the_seam_and_covers_every_orbit_camera():
    """Issue 31: the full orbit's last azimuth blends with its first; ±89° is covered."""
    from envstudio.methods.pem.bake.views import orbit_views, uncovered
    from envstudio.scene.camera import OrbitCamera

    base = OrbitCamera(azimuth=25.0, elevation=18.0, distance=3.0)
    space = orbit_views(base, 30.0, 20.0).describe()
    azimuths, elevations = np.array(space["azimuths"]), np.array(space["elevations"])
    assert space["closed"] and len(azimuths) == 12 and 25.0 in azimuths and 18.0 in elevations
    assert elevations.tolist() == [
        -89.0,
        -82.0,
        -62.0,
        -42.0,
        -22.0,
        -2.0,
        18.0,
        38.0,
        58.0,
        78.0,
        89.0,
    ]
    # midway between the last azimuth (355°) and the first (25° + 360°): half each
    b = view_blend(space, _eye(10.0, 18.0))
    row = int(np.argmin(np.abs(elevations - 18.0))) * len(azimuths)
    got = {v: w for v, w in zip(b.views, b.weights, strict=True) if w > 0}
    assert got.keys() == {row, row + 11} and np.allclose(list(got.values()), 0.5)
    # a sweep all the way round: weights sum to 1 and change by at most one step's worth
    sweep = np.linspace(-400.0, 400.0, 1601)
    dense = np.array([_image_weights(space, _eye(a, 18.0)) for a in sweep])
    assert np.allclose(dense.sum(axis=1), 1.0)
    assert np.abs(np.diff(dense, axis=0)).max() <= (sweep[1] - sweep[0]) / 30.0 + 1e-9
    # every orbit camera is inside; an arc leaves the rest outside
    cams = [OrbitCamera(azimuth=a, elevation=e) for a in (0.0, 200.0) for e in (-89.0, 0.0, 89.0)]
    assert uncovered(space, cams) == []
    arc = {**space, "closed": False, "azimuths": [20.0, 30.0], "elevations": [18.0]}
    assert len(uncovered(arc, [OrbitCamera(azimuth=25.0, elevation=18.0)])) == 0
    assert len(uncovered(arc, [OrbitCamera(azimuth=200.0, elevation=18.0)])) == 1
