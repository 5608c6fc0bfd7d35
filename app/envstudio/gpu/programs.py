"""Compiled GLSL programs, loaded from ``shaders/`` and cached per context.

A program is compiled once per (file, defines); changing a uniform never
recompiles. :attr:`ProgramLibrary.compile_count` lets tests assert that.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import moderngl

from envstudio.gpu.shader_source import STAGES, preprocess, stages_in
from envstudio.resources import shader_root


class ShaderCompileError(RuntimeError):
    """A shader failed to compile or link; the message names file and line."""


#: Plugins' shader folders by name: ``<name>/<file>`` is read from there.
_PLUGIN_FOLDERS: dict[str, Path] = {}


def add_shader_folder(folder: Path) -> None:
    """Read ``<folder.name>/<file>`` from ``folder`` (a plugin's own GLSL, its includes too)."""
    _PLUGIN_FOLDERS[folder.name] = folder


def shader_folder_names() -> set[str]:
    """Names a plugin's shader folder may not take: the shipped folders and those added."""
    return {p.name for p in shader_root().iterdir() if p.is_dir()} | set(_PLUGIN_FOLDERS)


def shader_path(name: str) -> Path:
    """The file of shader ``name`` (``folder/file.glsl``): a plugin's folder, else ``shaders/``."""
    folder, _, rest = name.partition("/")
    if folder in _PLUGIN_FOLDERS and rest:
        return _PLUGIN_FOLDERS[folder] / rest
    return shader_root() / name


def read_shader(name: str) -> str:
    """Return the text of shader ``name`` (:func:`shader_path`); raises ``FileNotFoundError``."""
    path = shader_path(name)
    if not path.is_file():
        raise FileNotFoundError(name)
    return path.read_text(encoding="utf-8")


_KWARG = {
    "VERTEX_SHADER": "vertex_shader",
    "GEOMETRY_SHADER": "geometry_shader",
    "FRAGMENT_SHADER": "fragment_shader",
}


class ProgramLibrary:
    """Programs of one context, cached by file name and defines.

    Parameters
    ----------
    ctx
        The context that owns the programs.
    """

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self._cache: dict[tuple, moderngl.Program | moderngl.ComputeShader] = {}
        self.compile_count = 0

    def get(self, name: str, defines: Mapping[str, object] | None = None) -> moderngl.Program:
        """Return the render program in ``name`` compiled with ``defines``."""
        key = (name, tuple(sorted((defines or {}).items())))
        if key not in self._cache:
            self._cache[key] = self._build(name, defines or {})
        return self._cache[key]

    def compute(
        self, name: str, defines: Mapping[str, object] | None = None
    ) -> moderngl.ComputeShader:
        """Return the compute shader in ``name`` compiled with ``defines``."""
        key = (name, tuple(sorted((defines or {}).items())), "compute")
        if key not in self._cache:
            source, smap = preprocess(name, "COMPUTE_SHADER", read_shader, defines)
            try:
                self._cache[key] = self.ctx.compute_shader(source)
            except moderngl.Error as exc:
                raise ShaderCompileError(f"{name}: {smap.translate(str(exc))}") from None
            self.compile_count += 1
        return self._cache[key]

    def _build(self, name: str, defines: Mapping[str, object]) -> moderngl.Program:
        text = read_shader(name)
        stages = [s for s in stages_in(text) if s in _KWARG]
        if "VERTEX_SHADER" not in stages:
            raise ShaderCompileError(f"{name}: no VERTEX_SHADER section")
        sources = {}
        maps = []
        for stage in STAGES:
            if stage in stages:
                src, smap = preprocess(name, stage, read_shader, defines)
                sources[_KWARG[stage]] = src
                maps.append(smap)
        try:
            program = self.ctx.program(**sources)
        except moderngl.Error as exc:
            message = str(exc)
            for smap in maps:
                message = smap.translate(message)
            raise ShaderCompileError(f"{name}: {message}") from None
        self.compile_count += 1
        return program

    def release(self) -> None:
        """Release every cached program; safe to call twice."""
        for program in self._cache.values():
            program.release()
        self._cache.clear()
