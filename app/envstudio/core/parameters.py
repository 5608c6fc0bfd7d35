"""Declared method parameters: name, type, range, default, unit and help.

The UI builds its panel from these declarations, the CLI parses ``--param
name=value`` with them, and the benchmark and comparison report list them.
Shared names (DESIGN.md): ``lod_bias`` (b), ``fresnel`` (f_λ),
``phong_exponent`` (N), ``kd`` (diffuse albedo).
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import asdict, dataclass

from envstudio.errors import ParameterError

KINDS = ("float", "int", "bool", "choice", "path", "color")


@dataclass(frozen=True)
class Parameter:
    """One declared parameter of a method.

    Attributes
    ----------
    name : str
        Identifier used by ``--param`` and as the GLSL uniform ``u_<name>``.
    kind : str
        ``float``, ``int``, ``bool``, ``choice``, ``path`` (a file name; the
        method checks the file when it uses it) or ``color`` (linear RGB, three
        floats; ``--param name=r,g,b``, one number for grey, or a preset's name).
    default : float | int | bool | str | tuple of float
        Value a fresh method starts with.
    minimum, maximum : float or None
        Inclusive range for numbers (for a colour, of each component).
    unit : str
        Unit or symbol shown beside the slider ("", "deg", "b", ...).
    help : str
        One sentence for tooltips and ``envstudio methods``.
    choices : tuple of str
        Allowed values of a ``choice``; of a ``path``, the file suffixes its
        dialog offers.
    log : bool
        Logarithmic slider (exponents).
    rebuild : bool
        Changing it needs a program rebuild (a mode switch), not only a uniform.
    presets : dict or tuple
        A ``color``'s named values: name → (r, g, b), stored as a tuple of pairs
        (``fresnel``'s are core/presets.py's f_λ of metals and dielectrics).
    applies_when : dict or tuple
        When it matters: another parameter's name → the choices under which it does
        (``{"model": ("banks",)}``), stored as a tuple of pairs. Empty: always. The panel
        greys it out otherwise; the CLI accepts it anyway.
    """

    name: str
    kind: str
    default: float | int | bool | str | tuple[float, float, float]
    minimum: float | None = None
    maximum: float | None = None
    unit: str = ""
    help: str = ""
    choices: tuple[str, ...] = ()
    log: bool = False
    rebuild: bool = False
    applies_when: Mapping[str, str | tuple[str, ...]] | tuple = ()
    presets: Mapping[str, tuple[float, float, float]] | tuple = ()

    def __post_init__(self):
        if isinstance(self.presets, Mapping):
            pairs = tuple((name, tuple(rgb)) for name, rgb in self.presets.items())
            object.__setattr__(self, "presets", pairs)
        conditions = self.applies_when
        if isinstance(conditions, Mapping):
            pairs = tuple(
                (name, (allowed,) if isinstance(allowed, str) else tuple(allowed))
                for name, allowed in conditions.items()
            )
            object.__setattr__(self, "applies_when", pairs)
        if self.kind not in KINDS:
            raise ValueError(f"parameter {self.name}: kind {self.kind!r} not in {KINDS}")
        self.validate(self.default)

    def validate(self, value: object) -> float | int | bool | str | tuple[float, float, float]:
        """Return ``value`` converted to this parameter's type, or raise ParameterError."""
        if self.kind == "color":
            return self._color(value)
        if self.kind == "bool":
            if isinstance(value, bool):
                return value
            text = str(value).strip().lower()
            if text in ("1", "true", "on", "yes"):
                return True
            if text in ("0", "false", "off", "no"):
                return False
            raise ParameterError(f"{self.name}={value}: expected true or false")
        if self.kind == "path":
            if not isinstance(value, (str, bytes)) and not hasattr(value, "__fspath__"):
                raise ParameterError(f"{self.name}={value!r}: expected a file name")
            return str(value)
        if self.kind == "choice":
            if str(value) not in self.choices:
                raise ParameterError(
                    f"{self.name}={value}: expected one of {', '.join(self.choices)}"
                )
            return str(value)
        try:
            number = int(value) if self.kind == "int" else float(value)
        except (TypeError, ValueError):
            raise ParameterError(f"{self.name}={value}: expected {self._expected()}") from None
        if self.kind == "int" and float(value) != number:
            raise ParameterError(f"{self.name}={value}: expected {self._expected()}")
        if (
            number != number
            or (self.minimum is not None and number < self.minimum)
            or (self.maximum is not None and number > self.maximum)
        ):
            raise ParameterError(f"{self.name}={value}: expected {self._expected()}")
        return number

    def _color(self, value: object) -> tuple[float, float, float]:
        """``r,g,b``, one number (grey), a preset's name, or three numbers; each finite and
        inside the range."""
        presets = dict(self.presets)
        if isinstance(value, str) and value.strip().lower() in presets:
            return presets[value.strip().lower()]
        parts = value.split(",") if isinstance(value, str) else value
        if isinstance(parts, numbers.Real) and not isinstance(parts, bool):
            parts = (parts,)
        try:
            rgb = tuple(float(c) for c in parts)
        except (TypeError, ValueError):
            rgb = ()
        if len(rgb) == 1:
            rgb = rgb * 3
        low = -float("inf") if self.minimum is None else self.minimum
        high = float("inf") if self.maximum is None else self.maximum
        if len(rgb) != 3 or not all(low <= c <= high and abs(c) != float("inf") for c in rgb):
            named = f", or one of {', '.join(presets)}" if presets else ""
            raise ParameterError(
                f"{self.name}={value}: expected r,g,b or one number (grey), each in "
                f"[{low:g}, {high:g}]{named}"
            )
        return rgb

    def applies(self, values: ParameterValues | Mapping[str, object]) -> bool:
        """Whether it matters under ``values`` (:attr:`applies_when`; a name they lack: yes)."""
        return all(
            name not in values or str(values[name]) in allowed
            for name, allowed in self.applies_when
        )

    def _expected(self) -> str:
        kind = "an integer" if self.kind == "int" else "a number"
        return f"{kind} in [{self.minimum:g}, {self.maximum:g}]"

    def describe(self) -> dict:
        """JSON-ready description (a colour's default as a list)."""
        described = asdict(self)
        described["applies_when"] = {name: list(allowed) for name, allowed in self.applies_when}
        described["presets"] = {name: list(rgb) for name, rgb in self.presets}
        if self.kind == "color":
            described["default"] = list(self.default)
        return {k: v for k, v in described.items() if k == "default" or v not in (None, (), "", {})}


class ParameterValues:
    """Current values of a method's parameters, validated on every assignment.

    Parameters
    ----------
    declarations
        The method's parameters.
    """

    def __init__(self, declarations: Iterable[Parameter]):
        self._decl = {p.name: p for p in declarations}
        self._values = {p.name: p.default for p in self._decl.values()}
        self.revision = 0

    def __getitem__(self, name: str):
        return self._values[self._declared(name).name]

    def __setitem__(self, name: str, value) -> None:
        value = self._declared(name).validate(value)
        if value != self._values[name]:
            self._values[name] = value
            self.revision += 1

    def __contains__(self, name: str) -> bool:
        return name in self._decl

    def __iter__(self) -> Iterator[Parameter]:
        return iter(self._decl.values())

    def as_dict(self) -> dict[str, float | int | bool | str]:
        """Name → current value."""
        return dict(self._values)

    def update(self, values: dict[str, object], ignore_unknown: bool = False) -> None:
        """Assign several values; unknown names raise unless ``ignore_unknown``."""
        for name, value in values.items():
            if ignore_unknown and name not in self._decl:
                continue
            self[name] = value

    def _declared(self, name: str) -> Parameter:
        if name not in self._decl:
            known = ", ".join(self._decl) or "none"
            raise ParameterError(f"unknown parameter {name!r} (this method has: {known})")
        return self._decl[name]


def parse_assignments(items: Iterable[str]) -> dict[str, str]:
    """Parse ``name=value`` strings from the command line."""
    result = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ParameterError(f"--param {item!r}: expected name=value")
        result[name.strip()] = value.strip()
    return result
