"""Tangent fields of anisotropic materials (plain data and NumPy, no GL).

An anisotropic BRDF (the Banks model of seed 004 §5.3) needs a unit tangent t
orthogonal to the normal at every vertex: the direction of the brushing or of
the fibres. :class:`TangentField` says where it comes from:

- ``axis``: around an axis a through the mesh centre c, t ∝ a × (p − c) (a
  brushed teapot, a turned bowl: circles about a);
- ``direction``: along a fixed direction a, t ∝ a − ⟨a,n⟩ n;
- ``radial``: away from the axis, t ∝ r − ⟨r,n⟩ n with r = (p − c) − ⟨p − c, a⟩ a
  (a disc brushed outwards);
- ``uv``: the mesh's texture u direction ∂p/∂u (per triangle from the UV
  gradients, summed at the vertices), where the mesh has UVs.

Every field is projected into the tangent plane (t − ⟨t,n⟩ n) and normalised.
Where it is degenerate (on the axis, a normal along the direction, triangles
with collapsed UVs) the vertex takes any unit vector orthogonal to n
(:func:`perpendicular`) instead of a NaN. The vectors are in the mesh's own
coordinates; a renderer transforms them by the model matrix.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from envstudio.scene.mesh import MeshData

#: The field kinds, in the order the UI lists them.
FIELDS = ("axis", "direction", "radial", "uv")
#: The axes a field may use, by name.
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
#: Below this length a projected tangent counts as degenerate.
DEGENERATE = 1e-6


@dataclass(frozen=True)
class TangentField:
    """Where a material's tangents come from (module docstring).

    Attributes
    ----------
    kind : str
        One of :data:`FIELDS`.
    axis : str
        ``x``, ``y`` or ``z``: the axis of ``axis`` and ``radial``, the
        direction of ``direction`` (mesh coordinates).
    """

    kind: str = "axis"
    axis: str = "y"

    def __post_init__(self):
        if self.kind not in FIELDS:
            raise ValueError(f"tangent_field={self.kind}: expected one of {', '.join(FIELDS)}")
        if self.axis not in AXES:
            raise ValueError(f"tangent_axis={self.axis}: expected one of {', '.join(AXES)}")


@dataclass(frozen=True)
class Tangents:
    """Unit tangents of a mesh's vertices and how they were found.

    Attributes
    ----------
    vectors : (n, 3) float32
        Unit, orthogonal to the vertex normals (|⟨t,n⟩| < 1e-5), mesh coordinates.
    kind : str
        The field actually used (``uv`` falls back to ``axis`` without UVs).
    note : str
        Why the field fell back, for the UI and the CLI; empty if it did not.
    degenerate : int
        Vertices where the field was degenerate and :func:`perpendicular` was used.
    """

    vectors: npt.NDArray[np.float32]
    kind: str
    note: str = ""
    degenerate: int = 0


def perpendicular(normals: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """(n, 3) unit vectors orthogonal to unit ``normals``: n × e for the least aligned axis e."""
    e = np.zeros_like(normals)
    e[np.arange(len(normals)), np.argmin(np.abs(normals), axis=1)] = 1.0
    t = np.cross(normals, e)
    return t / np.linalg.norm(t, axis=1, keepdims=True)


def mesh_tangents(mesh: MeshData, field: TangentField) -> Tangents:
    """The tangents of ``field`` at every vertex of ``mesh``.

    Parameters
    ----------
    mesh
        The mesh; its normals need not be exactly unit.
    field
        Where the tangents come from.

    Returns
    -------
    Tangents
        ``uv`` on a mesh without UVs falls back to ``axis`` with a note.
    """
    n = mesh.normals.astype(np.float64)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-30)
    p = mesh.positions.astype(np.float64)
    axis = np.asarray(AXES[field.axis])
    centre = mesh.bounds().mean(axis=0).astype(np.float64)
    kind, note = field.kind, ""
    if kind == "uv" and mesh.uvs is None:
        kind = "axis"
        note = f"{mesh.name} has no texture coordinates: tangents around the {field.axis} axis"
    if kind == "axis":
        raw = np.cross(axis, p - centre)
    elif kind == "direction":
        raw = np.broadcast_to(axis, p.shape)
    elif kind == "radial":
        offset = p - centre
        raw = offset - (offset @ axis)[:, None] * axis
    else:
        raw = _uv_directions(mesh)
    t = raw - np.sum(raw * n, axis=1, keepdims=True) * n
    length = np.linalg.norm(t, axis=1)
    bad = ~(length > DEGENERATE * max(float(np.abs(raw).max(initial=0.0)), 1e-30))
    t = np.where(bad[:, None], 0.0, t / np.where(bad, 1.0, length)[:, None])
    if bad.any():
        t[bad] = perpendicular(n[bad])
    return Tangents(t.astype(np.float32), kind, note, int(bad.sum()))


def _uv_directions(mesh: MeshData) -> npt.NDArray[np.float64]:
    """(n, 3) sums over each vertex's triangles of ∂p/∂u (area-weighted by construction).

    Per triangle, with edges e₁ = p₁ − p₀, e₂ = p₂ − p₀ and UV edges (Δu, Δv):
    ∂p/∂u · det = Δv₂ e₁ − Δv₁ e₂, det = Δu₁Δv₂ − Δu₂Δv₁; the sign of det keeps
    the direction of increasing u, and triangles with det = 0 add nothing.
    """
    p = mesh.positions.astype(np.float64)
    uv = mesh.uvs.astype(np.float64)
    i0, i1, i2 = mesh.indices.T
    e1, e2 = p[i1] - p[i0], p[i2] - p[i0]
    d1, d2 = uv[i1] - uv[i0], uv[i2] - uv[i0]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    du = (d2[:, 1:2] * e1 - d1[:, 1:2] * e2) * np.sign(det)[:, None]
    out = np.zeros_like(p)
    for corner in (i0, i1, i2):
        np.add.at(out, corner, du)
    return out
