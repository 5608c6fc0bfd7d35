"""The method registry: every plugin of the entry-point group ``envstudio.methods``.

envmap-studio's own methods are entry points of its distribution, loaded
exactly as another package's are. Their declared :attr:`Plugin.order` sets the
order of the switch, the keys and ``envstudio methods``; another distribution's
methods follow, by their order, then name. A plugin that fails to import, names
neither a :class:`Method` subclass nor a :class:`Plugin`, or declares a method
name, figure, bake, command or bench flag already taken, is left out with one
line on stderr naming it and what went wrong; every other method works.
"""

from __future__ import annotations

import importlib.metadata
import re
import sys
from dataclasses import dataclass
from functools import cache

from envstudio.engine.hooks import Plugin
from envstudio.engine.method import Method
from envstudio.errors import ParameterError
from envstudio.gpu.programs import add_shader_folder, shader_folder_names

ENTRY_POINT_GROUP = "envstudio.methods"
SHIPPED_DISTRIBUTION = "envmap-studio"
_METHOD_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass(frozen=True)
class Registry:
    """The loaded plugins, in order, and what each adds.

    Attributes
    ----------
    plugins : tuple of Plugin
        In the declared order (shipped first).
    warnings : tuple of str
        One line per plugin left out.
    """

    plugins: tuple[Plugin, ...]
    warnings: tuple[str, ...]

    def methods(self) -> dict[str, type[Method]]:
        """Method classes by name, in order."""
        return {plugin.name: plugin.method for plugin in self.plugins}

    def hooks(self, kind: str) -> dict[str, tuple[str, object]]:
        """Every hook of ``kind`` (``figures``, ``bakes``, ``commands``, ``bench_tables``)
        by its name on the command line, with the method that declares it."""
        key = {"figures": "name", "bakes": "kind", "commands": "name", "bench_tables": "flag"}[kind]
        return {
            getattr(hook, key): (plugin.name, hook)
            for plugin in self.plugins
            for hook in getattr(plugin, kind)
        }


def _plugin_of(loaded: object) -> Plugin:
    if isinstance(loaded, Plugin):
        return loaded
    if isinstance(loaded, type) and issubclass(loaded, Method):
        return Plugin(method=loaded)
    raise TypeError(f"names {loaded!r}, expected a Method subclass or an envstudio.plugin.Plugin")


def _is_shipped(entry_point: importlib.metadata.EntryPoint) -> bool:
    dist = getattr(entry_point, "dist", None)
    name = "" if dist is None else dist.metadata["Name"] or ""
    return re.sub(r"[-_.]+", "-", name).lower() == SHIPPED_DISTRIBUTION


def _conflict(plugin: Plugin, taken: dict[str, set[str]]) -> str | None:
    """Why ``plugin`` clashes with those accepted before it (None when it does not)."""
    name = plugin.name
    if not isinstance(name, str) or not _METHOD_NAME.match(name):
        return f"method name {name!r}: expected lower-case letters, digits and _"
    if name in taken["method"]:
        return f"method name {name!r} is already taken"
    for kind, names in (
        ("figure", [f.name for f in plugin.figures]),
        ("bake", [b.kind for b in plugin.bakes]),
        ("command", [c.name for c in plugin.commands]),
        ("bench flag", [t.flag for t in plugin.bench_tables]),
    ):
        clash = sorted(set(names) & taken[kind])
        if clash:
            return f"{kind} {clash[0]!r} is already taken"
    if plugin.shaders is not None:
        if not plugin.shaders.is_dir():
            return f"shader folder {plugin.shaders} does not exist"
        if plugin.shaders.name in shader_folder_names():
            return f"shader folder name {plugin.shaders.name!r} is already taken"
    return None


def _claim(plugin: Plugin, taken: dict[str, set[str]]) -> None:
    taken["method"].add(plugin.name)
    taken["figure"].update(f.name for f in plugin.figures)
    taken["bake"].update(b.kind for b in plugin.bakes)
    taken["command"].update(c.name for c in plugin.commands)
    taken["bench flag"].update(t.flag for t in plugin.bench_tables)
    if plugin.shaders is not None:
        add_shader_folder(plugin.shaders)


def load_registry() -> Registry:
    """Load every plugin of :data:`ENTRY_POINT_GROUP` (each entry point once)."""
    found: dict[tuple[str, str], importlib.metadata.EntryPoint] = {}
    for entry_point in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        found.setdefault((entry_point.name, entry_point.value), entry_point)
    loaded, warnings = [], []
    for entry_point in found.values():
        label = f"plugin {entry_point.name} ({entry_point.value})"
        try:
            plugin = _plugin_of(entry_point.load())
        except Exception as error:  # any failure of foreign code: one line
            warnings.append(f"{label}: {type(error).__name__}: {error}".splitlines()[0])
            continue
        loaded.append((not _is_shipped(entry_point), plugin.order, str(plugin.name), plugin, label))
    taken: dict[str, set[str]] = {k: set() for k in ("method", "figure", "bake", "command")}
    taken["bench flag"] = set()
    plugins = []
    for *_, plugin, label in sorted(loaded, key=lambda item: item[:3]):
        problem = _conflict(plugin, taken)
        if problem:
            warnings.append(f"{label}: {problem}; left out")
            continue
        _claim(plugin, taken)
        plugins.append(plugin)
    return Registry(tuple(plugins), tuple(warnings))


@cache
def registry() -> Registry:
    """The process's registry, loaded on first use; its warnings go to stderr once."""
    loaded = load_registry()
    for line in loaded.warnings:
        print(f"envstudio: warning: {line}", file=sys.stderr)
    return loaded


def available_methods() -> dict[str, type[Method]]:
    """Registered methods by name, in the declared order."""
    return registry().methods()


def method_class(name: str) -> type[Method]:
    """The registered method called ``name``; raises ParameterError if unknown."""
    methods = available_methods()
    if name not in methods:
        raise ParameterError(f"unknown method {name!r} (available: {', '.join(methods)})")
    return methods[name]


def ground_truth_class() -> type[Method]:
    """The method the others are measured against (the plugin declared ``ground_truth``)."""
    for plugin in registry().plugins:
        if plugin.ground_truth:
            return plugin.method
    raise ParameterError("no ground-truth method is registered (envmap-studio's reference)")
