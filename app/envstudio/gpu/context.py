"""OpenGL context creation for headless work (EGL) with a clear error when impossible."""

from __future__ import annotations

import contextlib

import moderngl

from envstudio.errors import ContextError, ParameterError

REQUIRED_VERSION = 330
PREFERRED_VERSION = 430


def create_headless_context() -> moderngl.Context:
    """Create a standalone OpenGL core context through EGL (no display needed).

    4.3 (compute shaders: kautz's dynamic mode and cross-face filter) is asked
    for first, because NVIDIA's EGL gives exactly the version requested and a
    3.3 request gets 3.3; 3.3 is the fallback. On a machine without a GPU this
    is Mesa's llvmpipe, which answers 4.5 either way.

    Raises
    ------
    ContextError
        If EGL or a 3.3 context is unavailable; the message says what to install.
    """
    with contextlib.suppress(Exception):
        return moderngl.create_context(standalone=True, backend="egl", require=PREFERRED_VERSION)
    try:
        ctx = moderngl.create_context(standalone=True, backend="egl", require=REQUIRED_VERSION)
    except Exception as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ContextError(
            f"no OpenGL {REQUIRED_VERSION // 100}.{REQUIRED_VERSION % 100 // 10} context through "
            f"EGL ({first}); install libegl1 libegl-mesa0 libgl1-mesa-dri or a GPU driver"
        ) from None
    return ctx


def is_software_renderer(ctx: moderngl.Context) -> bool:
    """True for software rasterisers (llvmpipe, softpipe, swrast) whose timer queries lie."""
    renderer = ctx.info.get("GL_RENDERER", "").lower()
    return any(name in renderer for name in ("llvmpipe", "softpipe", "swrast", "software"))


def describe(ctx: moderngl.Context) -> str:
    """One line naming the renderer and GL version."""
    return f"{ctx.info.get('GL_RENDERER', '?')} | {ctx.info.get('GL_VERSION', '?')}"


def has_compute(ctx: moderngl.Context) -> bool:
    """True when ``ctx`` has compute shaders and image load/store (OpenGL 4.3 or later)."""
    return ctx.version_code >= PREFERRED_VERSION


def require_version(ctx: moderngl.Context, version: int, what: str) -> None:
    """Raise a one-line :class:`ParameterError` when ``ctx`` is older than ``version`` (430 = 4.3).

    ``what`` names the feature and why it needs the version, e.g. "dynamic=true needs
    OpenGL 4.3 compute shaders".
    """
    if ctx.version_code < version:
        have = f"{ctx.version_code // 100}.{ctx.version_code % 100 // 10}"
        raise ParameterError(f"{what}; this context is {have}")
