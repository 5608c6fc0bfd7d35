"""The GPU memory a method holds, estimated from its textures and buffers."""

from __future__ import annotations

import moderngl

__all__ = ["gpu_bytes"]

_DTYPE_BYTES = {"f1": 1, "u1": 1, "i1": 1, "f2": 2, "u2": 2, "i2": 2, "f4": 4, "u4": 4, "i4": 4}
#: Object attributes followed this deep from the method.
_DEPTH = 4


def gpu_bytes(owner: object) -> int:
    """Bytes of every texture and buffer reachable from ``owner``'s attributes.

    A texture with a mipmap filter counts 4/3 of its level 0 (a full chain); a
    cube counts six faces. Objects reached twice count once. An estimate: what
    the driver pads or keeps besides (programs, framebuffers) is not counted.

    Parameters
    ----------
    owner
        A method (or anything holding moderngl objects in attributes, lists,
        tuples and dicts, up to 4 levels deep).
    """
    seen: set[int] = set()
    return _walk(owner, seen, _DEPTH)


def _walk(obj: object, seen: set[int], depth: int) -> int:
    if id(obj) in seen or depth < 0:
        return 0
    seen.add(id(obj))
    if isinstance(obj, moderngl.Buffer):
        return int(obj.size)
    if isinstance(obj, (moderngl.Texture, moderngl.TextureCube, moderngl.Texture3D)):
        return _texture_bytes(obj)
    if isinstance(obj, moderngl.TextureArray):
        w, h, layers = obj.size
        return w * h * layers * obj.components * _DTYPE_BYTES.get(obj.dtype, 4)
    if isinstance(obj, dict):
        return sum(_walk(v, seen, depth - 1) for v in obj.values())
    if isinstance(obj, (list, tuple)):
        return sum(_walk(v, seen, depth - 1) for v in obj)
    if hasattr(obj, "__dict__") and not isinstance(obj, (type, moderngl.Context)):
        return sum(_walk(v, seen, depth - 1) for v in vars(obj).values())
    return 0


def _texture_bytes(tex) -> int:
    size = tex.size
    texels = size[0] * size[1] * (size[2] if len(size) > 2 else 1)
    if isinstance(tex, moderngl.TextureCube):
        texels *= 6
    base = texels * tex.components * _DTYPE_BYTES.get(tex.dtype, 4)
    mipmapped = tex.filter[0] in (
        moderngl.LINEAR_MIPMAP_LINEAR,
        moderngl.LINEAR_MIPMAP_NEAREST,
        moderngl.NEAREST_MIPMAP_LINEAR,
        moderngl.NEAREST_MIPMAP_NEAREST,
    )
    return base * 4 // 3 if mipmapped else base
