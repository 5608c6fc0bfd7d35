"""glTF ``EXT_lights_image_based``: an image-based light as a glTF document with its images.

Written from the extension (KhronosGroup/glTF, extensions/2.0/Vendor/EXT_lights_image_based:
README.md and schema/light.schema.json). The document holds one light and one scene that
uses it::

    "extensionsUsed": ["EXT_lights_image_based"],
    "extensions": {"EXT_lights_image_based": {"lights": [{
        "intensity", "rotation",                 quaternion (x, y, z, w)
        "irradianceCoefficients": 9 × 3,
        "specularImageSize": n,
        "specularImages": K × 6 indices into "images" (mip k, faces +X, −X, +Y, −Y, +Z, −Z),
        "extras": {kernel, roughness per level, the KTX2 file}}]}},
    "scenes": [{"extensions": {"EXT_lights_image_based": {"light": 0}}}], "images": [...]

- **irradianceCoefficients**: the SH coefficients of the irradiance E(n), in the order
  and basis of core.sh (seed 000 eq. 9: Y0; y, z, x; xy, yz, 3z² − 1, xz, x² − y², with
  their normalisation constants): row i is Â_i L_i (Ramamoorthi & Hanrahan 2001 eq. 7's
  clamped-cosine convolution, Â = π, 2π/3, π/4), RGB, so that E(n) = Σ_i row_i Y_i(n).
  This is the convention Babylon.js's loader reads (``SphericalHarmonics.FromArray`` in the
  order l00, l1−1, l10, l11, l2−2, l2−1, l20, l21, l22, then
  ``convertIrradianceToLambertianRadiance``: E/π), in the glTF frame (+Y up,
  right-handed), which is the project's world frame.
- **specularImages**: one PNG per face and level, 4-channel, so RGBD as the extension
  requires of a 4-channel PNG: A = D = clamp(⌊max(255 / max(r, g, b), 1)⌋ / 255, 0, 1),
  RGB = (D · rgb)^(1/2.2) clamped to [0, 1], decoded as rgb = RGB^2.2 / A (Babylon.js's
  toRGBD / fromRGBD, the extension's reference runtime). Faces are the cube's as the KTX2
  file and OpenGL hold them (first row = the face's top as seen from inside the cube,
  ``rd``); they are not flipped for glTF's texture space (the README's note), since the
  faces are read by a cube sampler, not by texture coordinates.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt
import OpenImageIO as oiio

from envstudio.core.sh import A_HAT
from envstudio.io.atomic import atomic_path, write_text_atomic

__all__ = ["FACE_NAMES", "decode_rgbd", "encode_rgbd", "write_lights_image_based"]

#: Face suffixes of the image files, in the extension's (and OpenGL's) order.
FACE_NAMES = ("px", "nx", "py", "ny", "pz", "nz")
_GAMMA = 2.2
_RGBD_RANGE = 255.0


def encode_rgbd(rgb: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    """(…, 3) linear radiance → (…, 4) uint8 RGBD (module docstring)."""
    rgb = np.maximum(np.asarray(rgb, dtype=np.float64), 0.0)
    peak = np.maximum(rgb.max(axis=-1, keepdims=True), 1e-7)
    d = np.clip(np.floor(np.maximum(_RGBD_RANGE / peak, 1.0)) / 255.0, 0.0, 1.0)
    encoded = np.clip(rgb * d, 0.0, 1.0) ** (1.0 / _GAMMA)
    return np.rint(np.concatenate([encoded, d], axis=-1) * 255.0).astype(np.uint8)


def decode_rgbd(rgbd: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """(…, 4) uint8 RGBD → (…, 3) linear radiance, rgb = RGB^2.2 / D."""
    values = np.asarray(rgbd, dtype=np.float64) / 255.0
    return values[..., :3] ** _GAMMA / np.maximum(values[..., 3:], 1.0 / 255.0)


def _write_rgbd_png(path: Path, rgbd: npt.NDArray[np.uint8]) -> Path:
    """Write (h, w, 4) bytes as an RGBA PNG exactly: D is data, not an opacity, so it is
    stored unassociated (OpenImageIO would otherwise divide RGB by it on the way out)."""
    spec = oiio.ImageSpec(rgbd.shape[1], rgbd.shape[0], 4, "uint8")
    spec.attribute("oiio:UnassociatedAlpha", 1)
    with atomic_path(path, need=rgbd.nbytes) as tmp:
        out = oiio.ImageOutput.create(str(tmp))
        if out is None or not out.open(str(tmp), spec):
            raise OSError(f"cannot write {path}: {oiio.geterror().strip()}")
        ok = out.write_image(np.ascontiguousarray(rgbd))
        if not (out.close() and ok):
            raise OSError(f"cannot write {path}: {out.geterror().strip()}")
    return path


def write_lights_image_based(
    path: str | os.PathLike,
    sh_radiance: npt.ArrayLike,
    levels: Sequence[npt.ArrayLike],
    *,
    intensity: float = 1.0,
    rotation: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
    extras: Mapping[str, object] | None = None,
) -> list[Path]:
    """Write the glTF document and its K × 6 RGBD PNGs beside it (``STEM_mK_FACE.png``).

    Parameters
    ----------
    path
        Output ``.gltf``.
    sh_radiance
        (9, 3) radiance SH coefficients L_i of core.sh (written as Â_i L_i).
    levels
        Mip levels, largest first, each (6, n_k, n_k, 3) linear radiance in core.cubemap order.
    intensity, rotation
        The light's brightness multiplier and orientation quaternion (x, y, z, w).
    extras
        Stored as the light's ``extras``.

    Returns
    -------
    list of Path
        The images, then the document (written last, so it never names a missing image).
    """
    path = Path(path)
    coefficients = np.asarray(sh_radiance, dtype=np.float64)
    if coefficients.shape != (9, 3):
        raise ValueError(f"sh_radiance must have shape (9, 3), got {coefficients.shape}")
    written, images, specular = [], [], []
    for k, level in enumerate(levels):
        faces = np.asarray(level, dtype=np.float32)
        row = []
        for face, name in zip(faces, FACE_NAMES, strict=True):
            image = path.with_name(f"{path.stem}_m{k}_{name}.png")
            written.append(_write_rgbd_png(image, encode_rgbd(face)))
            row.append(len(images))
            images.append({"uri": image.name, "mimeType": "image/png"})
        specular.append(row)
    light = {
        "name": path.stem,
        "intensity": float(intensity),
        "rotation": [float(v) for v in rotation],
        "irradianceCoefficients": (A_HAT[:, None] * coefficients).tolist(),
        "specularImageSize": int(np.asarray(levels[0]).shape[1]),
        "specularImages": specular,
    }
    if extras:
        light["extras"] = dict(extras)
    document = {
        "asset": {"version": "2.0", "generator": "envstudio prefilter"},
        "extensionsUsed": ["EXT_lights_image_based"],
        "extensions": {"EXT_lights_image_based": {"lights": [light]}},
        "scene": 0,
        "scenes": [{"extensions": {"EXT_lights_image_based": {"light": 0}}}],
        "images": images,
    }
    write_text_atomic(path, json.dumps(document, indent=2) + "\n")
    return [*written, path]
