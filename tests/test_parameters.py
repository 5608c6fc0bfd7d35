"""Parameter declarations: validation, messages, the registry's descriptions."""

import pytest

from envstudio.core.parameters import Parameter, ParameterValues, parse_assignments
from envstudio.engine.registry import available_methods, method_class
from envstudio.errors import ParameterError


def test_values_are_validated_and_converted():
    values = ParameterValues(
        [
            Parameter("lod_bias", "float", 0.0, 0.0, 10.0, "b"),
            Parameter("steps", "int", 4, 1, 64),
            Parameter("on", "bool", False),
            Parameter("mode", "choice", "a", choices=("a", "b")),
        ]
    )
    values["lod_bias"] = "2.5"
    values["steps"] = "8"
    values["on"] = "true"
    values["mode"] = "b"
    assert values.as_dict() == {"lod_bias": 2.5, "steps": 8, "on": True, "mode": "b"}
    assert values.revision == 4
    values["lod_bias"] = 2.5
    assert values.revision == 4, "assigning the same value is not a change"


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("lod_bias", "12", r"lod_bias=12: expected a number in \[0, 10\]"),
        ("lod_bias", "abc", "lod_bias=abc: expected a number"),
        ("lod_bias", "nan", "expected a number"),
        ("steps", "2.5", "expected an integer"),
        ("on", "maybe", "expected true or false"),
        ("mode", "c", "expected one of a, b"),
        ("nope", "1", "unknown parameter 'nope'"),
    ],
)
def test_bad_values_name_the_value_and_what_was_expected(name, value, message):
    values = ParameterValues(
        [
            Parameter("lod_bias", "float", 0.0, 0.0, 10.0),
            Parameter("steps", "int", 4, 1, 64),
            Parameter("on", "bool", False),
            Parameter("mode", "choice", "a", choices=("a", "b")),
        ]
    )
    with pytest.raises(ParameterError, match=message):
        values[name] = value


def test_assignments_parse_and_reject_garbage():
    assert parse_assignments(["a=1", " b = x "]) == {"a": "1", "b": "x"}
    with pytest.raises(ParameterError, match="expected name=value"):
        parse_assignments(["novalue"])


def test_registry_describes_every_method_with_valid_defaults():
    methods = available_methods()
    assert "mirror" in methods
    for cls in methods.values():
        described = cls.describe()
        assert described["name"] == cls.name
        for p in cls.parameters:
            assert p.validate(p.default) == p.default
    with pytest.raises(ParameterError, match="unknown method 'phong'"):
        method_class("phong")


def test_parameters_say_when_they_apply():
    """The reference's Banks keys matter under model=banks only, rsibr's car-paint keys under
    brdf=carpaint: the panel greys the rest out, `methods --json` says so, --param takes them."""
    reference = {p.name: p for p in method_class("reference").parameters}
    for name in ("sharpness", "tangent_field", "tangent_axis", "normalize", "self_shadowing"):
        assert not reference[name].applies({"model": "phong"})
        assert reference[name].applies({"model": "banks"})
        assert reference[name].describe()["applies_when"] == {"model": ["banks"]}
    assert reference["phong_exponent"].applies({"model": "microfacet"})
    assert not reference["phong_exponent"].applies({"model": "banks"})
    assert all(p.applies({"model": "phong"}) for p in reference.values() if not p.applies_when)
    rsibr = {p.name: p for p in method_class("rsibr").parameters}
    for name in ("coat_f0", "metallic", "paint_red"):
        assert rsibr[name].applies({"brdf": "carpaint"}) and not rsibr[name].applies(
            {"brdf": "phong"}
        )
    banks = {p.name: p for p in method_class("banks").parameters}
    assert banks["sharpness"].applies_when == ()  # banks' own material always applies
    values = ParameterValues(method_class("reference").parameters)
    values["sharpness"] = 0.5  # accepted though it does not apply at the default model
    assert not reference["sharpness"].applies(values)
