"""Saved reference accumulations: ``compare`` resumes and reuses them.

A converged reference can take hours on a software renderer. ``compare`` saves
the accumulation (sums, squares, batch count, the last half-change and its
snapshot) every :data:`SAVE_INTERVAL_S` seconds and at the end, atomically, to
``<cache>/reference/<key>.npz``; a later run whose inputs give the same key
continues from it: an interrupted run resumes, and comparing another method
against the same reference costs nothing. The key is a SHA-256 of everything
the estimate depends on: the environment's pixels, every node's geometry,
transform, role and colour, the camera matrices, the image size, the
reference's parameters except those that only decide when to stop and how a
batch is drawn (``SCHEDULING_PARAMETERS``), and the text of the shaders that
compute it: the reference's programs and every file they include (both declared
by the ground truth's :meth:`GroundTruth.cache_identity`), so an edit to
another method's shader leaves saved accumulations valid. The cache folder is
``$ENVSTUDIO_CACHE_DIR``, else ``$XDG_CACHE_HOME/envstudio``, else
``~/.cache/envstudio``.

Keys change with every edit of a shader or a parameter, so old files are never
read again; after each save the least recently used files are deleted until
the folder holds at most ``$ENVSTUDIO_CACHE_MAX_MB`` megabytes (default
:data:`DEFAULT_LIMIT_MB`). Loading a file marks it used.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
import time
import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from envstudio.engine.method import Session
from envstudio.errors import ParameterError
from envstudio.io.atomic import atomic_path
from envstudio.io.cache_entries import discard
from envstudio.io.cache_folder import cache_folder
from envstudio.measure.ground_truth import GroundTruth

SAVE_INTERVAL_S = 60.0
DEFAULT_LIMIT_MB = 2048.0


def cache_dir() -> Path:
    """The folder holding envstudio's caches (not created here)."""
    return cache_folder()


def _add(digest, *arrays) -> None:
    for array in arrays:
        data = np.ascontiguousarray(array)
        digest.update(str((data.dtype, data.shape)).encode())
        digest.update(data.tobytes())


def scene_digest(session: Session):
    """The key's first part: the environment's pixels and every node (a ``hashlib`` object).

    Hashing a large environment takes tens of milliseconds; a caller that looks up
    many keys of one scene (the viewer's grid) makes it once and passes it to
    :func:`cache_path`.
    """
    digest = hashlib.sha256()
    scene = session.scene
    _add(digest, scene.environment.radiance)
    for node in scene.nodes:
        digest.update(node.role.encode())
        _add(digest, node.mesh.positions, node.mesh.normals, node.mesh.indices)
        _add(digest, node.transform.matrix(), np.asarray(node.color, np.float64))
    return digest


def cache_path(session: Session, reference: GroundTruth, size: tuple[int, int], scene=None) -> Path:
    """Where the accumulation of ``reference`` for this session's view and ``size`` is kept.

    ``scene``: :func:`scene_digest` of ``session``, when already made (it is copied).
    """
    digest = scene.copy() if scene is not None else scene_digest(session)
    camera = session.camera
    _add(digest, camera.view_matrix(), camera.projection_matrix(size[0] / size[1]))
    _add(digest, np.asarray(size))
    for part in reference.cache_identity():
        digest.update(part)
    return cache_dir() / reference.name / f"{digest.hexdigest()[:32]}.npz"


_HEADER_READERS = {
    (1, 0): np.lib.format.read_array_header_1_0,
    (2, 0): np.lib.format.read_array_header_2_0,
}


def saved_sizes(folder: Path) -> set[tuple[int, int]]:
    """The image sizes (w, h) of the accumulations saved in ``folder``, from their headers.

    The size is not in a file's name (the key is a digest), so a caller that must
    guess the size of a key (the viewer's grid) reads the (h, w, c) arrays'
    shapes, without their data. Unreadable files are skipped.
    """
    sizes = set()
    for path in folder.glob("*.npz"):
        with contextlib.suppress(OSError, ValueError, zipfile.BadZipFile):
            with zipfile.ZipFile(path) as archive:
                for name in archive.namelist():
                    with archive.open(name) as member:
                        version = np.lib.format.read_magic(member)
                        read_header = _HEADER_READERS.get(version)
                        shape = read_header(member)[0] if read_header else ()
                    if len(shape) == 3:
                        sizes.add((int(shape[1]), int(shape[0])))
    return sizes


def load_state(path: Path) -> dict[str, np.ndarray] | None:
    """The saved accumulation at ``path``; None when absent.

    An entry that does not load (truncated, bit-flipped, a folder, another
    program's file) or whose checksum does not match is discarded with a
    one-line note: the work is then done again.
    """
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            state = {name: data[name] for name in data.files}
        saved = str(state.pop("checksum"))
        if saved != state_checksum(state):
            raise ValueError("checksum mismatch")
        os.utime(path)  # used now: the last to be pruned
        return state
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as error:
        reason = str(error).splitlines()[0] if str(error) else type(error).__name__
        print(f"envstudio: note: {path}: unreadable ({reason}), discarded", file=sys.stderr)
        discard(path)
        return None


def state_checksum(state: dict[str, np.ndarray]) -> str:
    """SHA-256 (hex) of every array of ``state``: name, dtype, shape and bytes."""
    digest = hashlib.sha256()
    for name in sorted(state):
        array = np.ascontiguousarray(state[name])
        digest.update(f"{name} {array.dtype.str} {array.shape}".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


def save_state(path: Path, state: dict[str, np.ndarray]) -> None:
    """Write ``state`` with its checksum to ``path`` atomically (a crash leaves the previous
    file), then prune."""
    path.parent.mkdir(parents=True, exist_ok=True)
    checked = {**state, "checksum": np.array(state_checksum(state))}
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez(handle, **checked)
    prune(path.parent, path, cache_limit_bytes())


def cache_limit_bytes() -> int:
    """The cache's size limit: ``$ENVSTUDIO_CACHE_MAX_MB`` megabytes, else the default."""
    raw = os.environ.get("ENVSTUDIO_CACHE_MAX_MB")
    if raw is None:
        return int(DEFAULT_LIMIT_MB * 2**20)
    try:
        megabytes = float(raw)
    except ValueError:
        megabytes = float("nan")
    if not megabytes >= 0.0:
        raise ParameterError(f"ENVSTUDIO_CACHE_MAX_MB={raw!r}: expected megabytes, a number >= 0")
    return int(megabytes * 2**20)


def prune(folder: Path, keep: Path, limit: int) -> list[Path]:
    """Delete the least recently used saved accumulations in ``folder`` beyond ``limit`` bytes.

    Parameters
    ----------
    folder
        The cache's ``reference`` folder; only its ``*.npz`` files are counted.
    keep
        The file just written: never deleted, even alone over the limit.
    limit
        Bytes the folder may hold.

    Returns
    -------
    list of Path
        The deleted files, oldest first.
    """
    files = []
    for path in folder.glob("*.npz"):
        with contextlib.suppress(OSError):  # another process may delete it meanwhile
            stat = path.stat()
            files.append((stat.st_mtime, stat.st_size, path))
    total = sum(size for _, size, _ in files)
    deleted = []
    for _, size, path in sorted(files, key=lambda entry: entry[0]):
        if total <= limit:
            break
        if path == keep:
            continue
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
        total -= size
        deleted.append(path)
    return deleted


class Checkpoint:
    """Resume ``reference`` from its saved accumulation and save it as it goes.

    Parameters
    ----------
    session : Session
        The scene and camera the accumulation belongs to.
    reference : GroundTruth
        With its parameters set; :meth:`GroundTruth.resume` is called at
        once when a saved state exists.
    size : (int, int)
        Frame width and height in pixels.

    Attributes
    ----------
    path : Path
        The cache file (:func:`cache_path`).
    resumed_samples : int
        Samples per pixel taken from the saved state (0 when starting afresh).
    """

    def __init__(self, session: Session, reference: GroundTruth, size: tuple[int, int]):
        cache_limit_bytes()  # a bad $ENVSTUDIO_CACHE_MAX_MB fails here, not at the first save
        self.reference = reference
        self.path = cache_path(session, reference, size)
        state = load_state(self.path)
        self.resumed_samples = 0
        if state is not None:
            reference.resume(state)
            self.resumed_samples = reference.saved_samples(state)
        self._saved_at = time.perf_counter()

    def save_if_due(self) -> None:
        """Save when :data:`SAVE_INTERVAL_S` has passed since the last save."""
        if time.perf_counter() - self._saved_at > SAVE_INTERVAL_S:
            self.save()

    def save(self) -> None:
        """Save the accumulation now (atomically)."""
        save_state(self.path, self.reference.accumulation_state())
        self._saved_at = time.perf_counter()

    @contextlib.contextmanager
    def saved_on_interrupt(self) -> Iterator[None]:
        """Save when the block is interrupted (Ctrl-C; the CLI turns SIGTERM into one too)."""
        try:
            yield
        except KeyboardInterrupt:
            self.save()
            samples = self.reference.status.samples
            print(f"reference: saved at {samples} spp to {self.path}", file=sys.stderr)
            raise
