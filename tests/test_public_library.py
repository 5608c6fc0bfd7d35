"""Issue 39: the shipped methods build on ``envstudio.plugin`` and the public library only.

Walks every module under ``methods/`` (TYPE_CHECKING and function-level imports included)
and fails on an ``envstudio.*`` import outside :data:`envstudio.plugin.PUBLIC_LIBRARY` and
the method's own package, and, outside a GL-free ``bake/``, on a name taken from its home
module although ``envstudio.plugin`` exports it. The import-linter contracts say the same
in ``pyproject.toml``, configured by hand; this test keeps the two from drifting apart.
"""

from __future__ import annotations

import ast
import importlib.metadata
import sys
from pathlib import Path

import pytest

import envstudio.plugin as plugin
from envstudio.engine.registry import ENTRY_POINT_GROUP, SHIPPED_DISTRIBUTION

METHODS = Path(plugin.__file__).with_name("methods")


def module_imports(path: Path) -> list[tuple[int, str, list[str]]]:
    """(line, module, names) of every ``envstudio`` import in ``path``, at any depth."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.append((node.lineno, node.module, [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            found += [(node.lineno, a.name, []) for a in node.names]
    return [entry for entry in found if entry[1].split(".")[0] == "envstudio"]


def within(module: str, packages: tuple[str, ...]) -> bool:
    return any(module == p or module.startswith(p + ".") for p in packages)


def violations(path: Path) -> list[str]:
    """What ``path`` (a module under ``methods/``) imports that the contract forbids."""
    method = path.relative_to(METHODS).parts[0]
    own = f"envstudio.methods.{method}"
    in_bake = "bake" in path.relative_to(METHODS).parts[1:-1]
    exported = set(plugin.__all__)
    found = []
    for line, module, names in module_imports(path):
        where = f"{path.relative_to(METHODS.parent)}:{line}"
        if not within(module, (own, *plugin.PUBLIC_LIBRARY)):
            found.append(f"{where}: imports {module}, which is not public")
        elif module != "envstudio.plugin" and not in_bake and not within(module, (own,)):
            found += [
                f"{where}: {name} from {module}, not from envstudio.plugin"
                for name in names
                if name in exported
            ]
    return found


def test_every_method_module_imports_only_the_plugin_and_the_public_library():
    modules = sorted(METHODS.rglob("*.py"))
    assert len(modules) > 50, "the walk found too few modules"
    problems = [problem for path in modules for problem in violations(path)]
    assert problems == []


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        ("from envstudio.engine.session import RenderSession\n", "is not public"),
        ("from envstudio.methods.kautz.method import KautzMethod\n", "is not public"),
        ("def f():\n    from envstudio.measure import compare\n", "is not public"),
        ("from envstudio.gpu.uniforms import set_uniform\n", "not from envstudio.plugin"),
        ("import envstudio.ui.app\n", "is not public"),
    ],
)
def test_the_walk_catches_each_kind_of_private_import(tmp_path, source, expected, monkeypatch):
    fake = tmp_path / "methods"
    (fake / "mine").mkdir(parents=True)
    module = fake / "mine" / "method.py"
    module.write_text(source)
    monkeypatch.setattr(sys.modules[__name__], "METHODS", fake)
    (problem,) = violations(module)
    assert expected in problem


def test_every_shipped_method_package_is_one_entry_point():
    """The one registration place: each package under ``methods/`` is an entry point of the
    shipped distribution, and each entry point names its package's plugin."""
    shipped = {
        point.name: point.value
        for point in importlib.metadata.distribution(SHIPPED_DISTRIBUTION).entry_points
        if point.group == ENTRY_POINT_GROUP
    }
    packages = {p.name for p in METHODS.iterdir() if (p / "__init__.py").is_file()}
    assert set(shipped) == packages
    for name, value in shipped.items():
        assert value == f"envstudio.methods.{name}.plugin:PLUGIN"
