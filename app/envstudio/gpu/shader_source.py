"""GLSL preprocessing as plain strings: ``#include``, stage defines and ``#line``.

A program lives in one file with sections guarded by ``VERTEX_SHADER``,
``GEOMETRY_SHADER``, ``FRAGMENT_SHADER`` or ``COMPUTE_SHADER`` (the
moderngl-window ``ShaderSource`` convention). The file must start with a
``#version`` line. For each stage the preprocessor emits::

    #version ...            (the file's own line)
    #define VERTEX_SHADER   (the stage)
    #define NAME VALUE      (caller defines)
    #line 2 0               (so the compiler counts lines of the file itself)

``#include "common/x.glsl"`` is replaced by that file, once per program
(include guard semantics), wrapped in ``#line 1 k`` / ``#line n+1 parent`` so
every line the compiler reports maps back to a file and line. GLSL's ``#line``
takes a source-string *number*; :class:`SourceMap` keeps the number→file
table and :meth:`SourceMap.translate` rewrites driver messages (Mesa's
``0:12(3): error`` and NVIDIA's ``0(12) : error``) to ``file:line``.

Nothing here touches OpenGL, so it is tested without a GPU.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

STAGES = ("VERTEX_SHADER", "GEOMETRY_SHADER", "FRAGMENT_SHADER", "COMPUTE_SHADER")

_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"\s*$')
_VERSION = re.compile(r"^\s*#\s*version\b")
_MESA_MSG = re.compile(r"\b(\d+):(\d+)\((\d+)\)")
_NVIDIA_MSG = re.compile(r"\b(\d+)\((\d+)\)\s*:")


class ShaderSourceError(ValueError):
    """A shader file is malformed (no ``#version``, include cycle, missing include)."""


@dataclass
class SourceMap:
    """Source-string numbers of one preprocessed program, mapped to file names."""

    files: list[str] = field(default_factory=list)

    def number(self, name: str) -> int:
        """Return the source-string number of ``name``, adding it if new."""
        if name not in self.files:
            self.files.append(name)
        return self.files.index(name)

    def translate(self, message: str) -> str:
        """Rewrite ``N:L(C)`` / ``N(L) :`` locations in a compiler log to ``file:L``."""

        def mesa(match: re.Match) -> str:
            idx, line, col = (int(g) for g in match.groups())
            return f"{self._name(idx)}:{line}:{col}"

        def nvidia(match: re.Match) -> str:
            idx, line = (int(g) for g in match.groups())
            return f"{self._name(idx)}:{line} :"

        return _NVIDIA_MSG.sub(nvidia, _MESA_MSG.sub(mesa, message))

    def _name(self, idx: int) -> str:
        return self.files[idx] if 0 <= idx < len(self.files) else f"<source {idx}>"


def stages_in(text: str) -> list[str]:
    """Return the stage names whose define the file tests (its sections)."""
    return [stage for stage in STAGES if re.search(rf"\b{stage}\b", text)]


def preprocess(
    name: str,
    stage: str,
    read: Callable[[str], str],
    defines: Mapping[str, object] | None = None,
) -> tuple[str, SourceMap]:
    """Build the source of one stage of the program in file ``name``.

    Parameters
    ----------
    name
        Path of the program file relative to the shader root, e.g. ``"mirror/mirror.glsl"``.
    stage
        One of :data:`STAGES`.
    read
        Returns the text of a shader file given its relative path; raises
        ``FileNotFoundError`` when it does not exist.
    defines
        Extra ``#define NAME VALUE`` lines, in order.

    Returns
    -------
    source, source_map
        The GLSL text for the compiler and the table that maps its ``#line``
        numbers back to files.
    """
    if stage not in STAGES:
        raise ShaderSourceError(f"{name}: unknown stage {stage!r}, expected one of {STAGES}")
    text = _read(read, name, parent=None)
    lines = text.splitlines()
    if not lines or not _VERSION.match(lines[0]):
        raise ShaderSourceError(f"{name}: first line must be '#version ...'")
    smap = SourceMap()
    root = smap.number(name)
    out = [lines[0], f"#define {stage}"]
    out += [f"#define {key} {_glsl_value(value)}" for key, value in (defines or {}).items()]
    out.append(f"#line 2 {root}")
    included: set[str] = {name}
    out += _expand(name, lines[1:], 2, read, smap, included, stack=[name])
    return "\n".join(out) + "\n", smap


def _expand(
    name: str,
    lines: list[str],
    first_line: int,
    read: Callable[[str], str],
    smap: SourceMap,
    included: set[str],
    stack: list[str],
) -> list[str]:
    out: list[str] = []
    for offset, line in enumerate(lines):
        match = _INCLUDE.match(line)
        if not match:
            out.append(line)
            continue
        target = match.group(1)
        if target in stack:
            cycle = " -> ".join([*stack, target])
            raise ShaderSourceError(f"{name}: include cycle {cycle}")
        if target in included:
            out.append(f"// {target} already included")
            continue
        included.add(target)
        body = _read(read, target, parent=name).splitlines()
        out.append(f"#line 1 {smap.number(target)}")
        out += _expand(target, body, 1, read, smap, included, [*stack, target])
        out.append(f"#line {first_line + offset + 1} {smap.number(name)}")
    return out


def _read(read: Callable[[str], str], target: str, parent: str | None) -> str:
    try:
        return read(target)
    except FileNotFoundError:
        where = f"{parent}: included file" if parent else "shader file"
        raise ShaderSourceError(f"{where} {target!r} not found") from None


def _glsl_value(value: object) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    return str(value)
