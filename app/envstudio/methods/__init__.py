"""envmap-studio's methods, one plugin package each (entry points in pyproject.toml).

Each ``methods/<m>/`` holds everything about its technique: ``method.py`` (the
renderer), ``plugin.py`` (what it adds to the commands), its GL-free ``bake/``
where it has one, its commands, figures, bench tables and report sections. A
package here imports :mod:`envstudio.plugin` and the library below it, never
another method.
"""
