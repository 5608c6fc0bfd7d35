"""References that ``compare`` saved, found for the viewer's grid and measured against (issue 29).

``compare`` and the atlas save each reference accumulation under a key made of
everything it depends on (measure/ground_truth_cache.py): the scene, the camera,
the image size and the reference's parameters. :meth:`CachedReferences.find`
rebuilds that key for each of the grid's tiles:

- the scene and the camera are the viewer's. The size is not readable from a
  key, so every size saved in the cache folder is tried
  (:func:`ground_truth_cache.saved_sizes`), the largest first.
- the parameters are those of the viewer's reference (its panel), with the
  tile's reflectance model, the material values the tile shares with it (f_λ,
  k_d, the Banks lobe: what ``compare`` gives the reference of a group) and the
  tile's glossiness as a Phong exponent N, by :func:`match_glossiness` as
  ``compare`` matches. A key holds N to the last bit, and the round trip
  N → b → N does not, so the grid's own N (the matching hub's) and the derived
  N at 4 and 3 significant digits are tried too (``compare --param
  phong_exponent=100``). Both settings of ``untraced_too`` are tried: ``compare``
  turns it on where the reference traces.

:meth:`CachedReferences.measure` resumes the reference from its file and
resolves it without a new sample (its sample budget set to what it holds),
renders the tile's method at the reference's size under the same camera, one
sample per pixel as the tile shows it, and takes PSNR and FLIP (core/metrics.py)
of the two display images over the reference's coverage, as ``compare --ssaa 1``
does. The method is rendered at the reference's size rather than the
reference resampled to the tile's: resampling would add its own error to the
method's, and a tile of another aspect ratio is not the view the reference saw.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.core.images import displayed
from envstudio.core.metrics import MIN_SIZE, flip, psnr
from envstudio.engine.frame import FrameRenderer
from envstudio.engine.method import Method, Session
from envstudio.gpu.programs import ProgramLibrary
from envstudio.measure.ground_truth import UNTRACED_TOO
from envstudio.measure.ground_truth_cache import (
    cache_dir,
    cache_path,
    load_state,
    saved_sizes,
    scene_digest,
)
from envstudio.measure.matching import assign_clamped, match_glossiness

SIGNIFICANT_DIGITS = (4, 3)
"""Roundings of a derived Phong exponent also tried (a ``compare --param`` value)."""
MAX_FRAMES = 64
"""Frames a progressive method is given to finish at the reference's size."""


def render_finished(
    renderer: FrameRenderer, session: Session, method: Method, size: tuple[int, int]
) -> npt.NDArray[np.float32]:
    """``method``'s frame at ``size`` as it renders in ``session`` (camera, scene), given up to
    :data:`MAX_FRAMES` frames to finish (a progressive method); (h, w, 3) float32 HDR."""
    renderer.render_hdr(session.gpu_scene, method, session.camera, size)
    for _ in range(MAX_FRAMES - 1):
        if method.finished():
            break
        renderer.render_hdr(session.gpu_scene, method, session.camera, size)
    return renderer.read_hdr()


@dataclass(frozen=True)
class CachedReference:
    """A saved reference accumulation that matches a tile.

    Attributes
    ----------
    path : Path
        Its file in the cache.
    size : (int, int)
        Its image width and height, pixels.
    values : dict
        The reference's parameters it was accumulated with.
    """

    path: Path
    size: tuple[int, int]
    values: dict[str, object]


@dataclass(frozen=True)
class CachedNumbers:
    """A method against a cached reference: PSNR (dB), LDR-FLIP, and the reference's state."""

    psnr_db: float
    flip: float
    reference: str
    """The reference's status line (samples, noise, converged or not)."""


class CachedReferences:
    """Finds the saved references of a view and measures methods against them.

    Parameters
    ----------
    ctx, programs
        The context and its program cache.
    truth
        The ground truth's class (:func:`envstudio.engine.registry.ground_truth_class`).
    """

    def __init__(self, ctx: moderngl.Context, programs: ProgramLibrary, truth: type[Method]):
        self.truth = truth
        self._ctx, self._programs = ctx, programs
        self._reference: Method | None = None
        self._renderer: FrameRenderer | None = None
        self._resolved: tuple[tuple, npt.NDArray[np.float32], npt.NDArray[np.bool_], str] | None
        self._resolved = None

    @property
    def reference(self) -> Method:
        """The instance the keys are made and the saved states resolved with (made on use)."""
        if self._reference is None:
            self._reference = self.truth(self._ctx, self._programs)
        return self._reference

    def find(
        self,
        session: Session,
        template: Method,
        methods: Sequence[Method],
        hub: Method | None,
        cube_size: int,
    ) -> dict[str, CachedReference]:
        """The saved reference of each method of ``methods`` at the session's view, where one is.

        Parameters
        ----------
        session
            Its scene and camera are the view.
        template
            The ground truth whose parameters (the viewer's reference panel) the
            keys start from.
        methods
            The methods to find references for; the ground truth itself and methods
            of a model it cannot render are skipped.
        hub
            The method whose Phong exponent the grid matches through (None: none).
        cube_size
            Face edge n of the environment cube map (a LOD bias's N depends on it).

        Returns
        -------
        dict of str to CachedReference
            Method name → its reference; methods with none are left out.
        """
        folder = cache_dir() / self.truth.name
        sizes = sorted(saved_sizes(folder), key=lambda s: (-s[0] * s[1], s))
        if not sizes:
            return {}
        scene = scene_digest(session)
        keyed: dict[str, _Keyed] = {}  # candidates shared by tiles: their identity made once
        found = {}
        for method in methods:
            if method.name == self.truth.name or method.reflectance not in self.truth.models:
                continue
            for values in self.candidates(template, method, hub, cube_size):
                key = keyed.get(repr(values))
                if key is None:
                    self.reference.values.update(values)
                    key = keyed[repr(values)] = _Keyed(self.truth.name, self.reference)
                saved = _saved(session, key, sizes, scene)
                if saved is not None:
                    found[method.name] = CachedReference(*saved, values)
                    break
        return found

    def candidates(
        self, template: Method, method: Method, hub: Method | None, cube_size: int
    ) -> list[dict[str, object]]:
        """The reference parameters ``compare`` may have used for ``method``, likeliest first.

        See the module's docstring: the template's values with ``method``'s model,
        shared material values and matched N, then the other N and ``untraced_too``.
        """
        probe = self.reference.values
        probe.update(template.values.as_dict())
        probe["model"] = method.reflectance
        for declared in method.values:
            if declared.name in probe and declared.name != "model":
                # clamped to the reference's range (a plugin's may be wider): such a key
                # is never found, but the other tiles' lookups go on
                assign_clamped(self.reference, declared.name, method.values[declared.name])
        match_glossiness(self.reference, method, cube_size)
        derived = probe.as_dict()
        exponents = []
        if "phong_exponent" in derived:
            n = float(derived["phong_exponent"])
            exponents = [n]
            if hub is not None and "phong_exponent" in hub.values:
                exponents.append(float(hub.values["phong_exponent"]))
            exponents += [float(f"{n:.{digits}g}") for digits in SIGNIFICANT_DIGITS]
            exponents.append(float(template.values["phong_exponent"]))
        untraced = (
            [derived[UNTRACED_TOO], not derived[UNTRACED_TOO]] if UNTRACED_TOO in derived else []
        )
        result: list[dict[str, object]] = []
        for n in dict.fromkeys(exponents) if exponents else [None]:
            for flag in untraced or [None]:
                values = dict(derived)
                if n is not None:
                    values["phong_exponent"] = n
                if flag is not None:
                    values[UNTRACED_TOO] = flag
                if values not in result:
                    result.append(values)
        return result

    def measure(
        self,
        session: Session,
        method: Method,
        found: CachedReference,
        display: dict[str, object],
    ) -> CachedNumbers | None:
        """PSNR and FLIP of ``method`` at ``found``'s size against it (None: unreadable, too
        small, or no reflector in view).

        Parameters
        ----------
        session
            Its GPU scene and camera (the view ``found`` was found for).
        method
            Rendered at ``found.size`` under the camera, one sample per pixel.
        found
            From :meth:`find`.
        display
            Exposure and tone map of the display images.
        """
        if min(found.size) < MIN_SIZE:
            return None
        resolved = self._resolve(session, found, display)
        if resolved is None:
            return None
        truth, mask, status = resolved
        hdr = render_finished(self._frame_renderer(), session, method, found.size)
        shown = _display(hdr, display)
        return CachedNumbers(psnr(shown, truth, mask), flip(shown, truth, mask), status)

    def _resolve(self, session, found, display):
        """(display image, coverage, status line) of ``found``, resolved once per file and
        display setting; None when the file does not load or covers nothing."""
        key = (found.path, found.size, repr(sorted(display.items())))
        if self._resolved is not None and self._resolved[0] == key:
            return self._resolved[1:]
        state = load_state(found.path)
        if state is None:
            return None
        reference = self.reference
        reference.values.update(found.values)
        reference.frame_budget_ms = None
        reference.resume(state)
        budget = next(p for p in reference.values if p.name == "max_samples")
        samples = reference.saved_samples(state)
        reference.values["max_samples"] = int(np.clip(samples, budget.minimum, budget.maximum))
        renderer = self._frame_renderer()
        renderer.render_hdr(session.gpu_scene, reference, session.camera, found.size)
        mask = reference.coverage()
        if not mask.any():
            return None
        image = _display(renderer.read_hdr(), display)
        self._resolved = (key, image, mask, reference.status_line())
        return self._resolved[1:]

    def _frame_renderer(self) -> FrameRenderer:
        if self._renderer is None:
            self._renderer = FrameRenderer(self._ctx, self._programs)
        return self._renderer

    def forget(self) -> None:
        """Resolve the next reference anew (the scene or its environment changed)."""
        self._resolved = None

    def release(self) -> None:
        """Free the reference's and the renderer's GPU objects; safe twice."""
        for owner in (self._reference, self._renderer):
            if owner is not None:
                owner.release()
        self._reference = self._renderer = None
        self._resolved = None


def _saved(session, key, sizes, scene) -> tuple[Path, tuple[int, int]] | None:
    """The first of ``sizes`` whose file for ``key`` exists, and that file; None."""
    for size in sizes:
        path = cache_path(session, key, size, scene)
        if path.is_file():
            return path, size
    return None


class _Keyed:
    """A ground truth's name and :meth:`cache_identity` as they were when made (the identity
    reads its shaders' files: made once per candidate, not once per size)."""

    def __init__(self, name: str, reference: Method):
        self.name = name
        self._identity = reference.cache_identity()

    def cache_identity(self) -> list[bytes]:
        return self._identity


def _display(hdr: npt.NDArray[np.float32], display: dict[str, object]) -> npt.NDArray[np.float32]:
    """(h, w, 3) float32 display values, as compare's display images (core/images.py)."""
    exposure, tonemap = float(display["exposure"]), str(display["tonemap"])
    return displayed(hdr, exposure, tonemap).astype(np.float32)


def describe(found: CachedReference) -> str:
    """ "128×128, N = 100" : the reference's size and its Phong exponent where it has one."""
    w, h = found.size
    n = found.values.get("phong_exponent")
    return f"{w}×{h}" + (f", N = {n:g}" if isinstance(n, float) and math.isfinite(n) else "")
