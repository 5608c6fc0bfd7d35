"""Shader preprocessing as plain strings (no GPU): includes, stage defines, #line, errors."""

import pytest

from envstudio.gpu.programs import read_shader
from envstudio.gpu.shader_source import ShaderSourceError, preprocess, stages_in

FILES = {
    "prog.glsl": '#version 330 core\n#include "common/a.glsl"\nvoid main() {}\nlast line\n',
    "common/a.glsl": '// a line 1\n#include "common/b.glsl"\nfloat a() { return 1.0; }\n',
    "common/b.glsl": "float b() { return 2.0; }\n",
    "cycle.glsl": '#version 330 core\n#include "common/c1.glsl"\n',
    "common/c1.glsl": '#include "common/c2.glsl"\n',
    "common/c2.glsl": '#include "common/c1.glsl"\n',
    "twice.glsl": '#version 330 core\n#include "common/b.glsl"\n#include "common/b.glsl"\n',
    "noversion.glsl": "void main() {}\n",
    "missing.glsl": '#version 330 core\n#include "common/nope.glsl"\n',
}


def read(name: str) -> str:
    if name not in FILES:
        raise FileNotFoundError(name)
    return FILES[name]


def line_of(source: str, text: str) -> int:
    return source.splitlines().index(text)


def test_stage_define_and_version_come_first():
    source, _ = preprocess("prog.glsl", "FRAGMENT_SHADER", read, {"SAMPLES": 4, "FAST": True})
    lines = source.splitlines()
    assert lines[0] == "#version 330 core"
    assert lines[1] == "#define FRAGMENT_SHADER"
    assert "#define SAMPLES 4" in lines and "#define FAST 1" in lines
    assert lines[lines.index("#define FAST 1") + 1] == "#line 2 0"


def test_includes_are_expanded_recursively_with_line_directives():
    source, smap = preprocess("prog.glsl", "VERTEX_SHADER", read)
    lines = source.splitlines()
    assert "float a() { return 1.0; }" in lines and "float b() { return 2.0; }" in lines
    assert smap.files == ["prog.glsl", "common/a.glsl", "common/b.glsl"]
    # b starts at line 1 of source 2, then a resumes at its line 3, then prog at its line 3.
    b_at = line_of(source, "float b() { return 2.0; }")
    assert lines[b_at - 1] == "#line 1 2"
    assert lines[b_at + 1] == "#line 3 1"
    main_at = line_of(source, "void main() {}")
    assert lines[main_at - 1] == "#line 3 0"


def test_compiler_messages_are_mapped_to_files():
    _, smap = preprocess("prog.glsl", "VERTEX_SHADER", read)
    mesa = smap.translate("0:3(5): error: `x' undeclared\n2:1(7): error: bad")
    assert "prog.glsl:3:5: error" in mesa and "common/b.glsl:1:7: error" in mesa
    nvidia = smap.translate("1(3) : error C1008: undefined variable")
    assert nvidia.startswith("common/a.glsl:3 :")


def test_each_file_is_included_once():
    source, _ = preprocess("twice.glsl", "VERTEX_SHADER", read)
    assert source.count("float b()") == 1


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("cycle.glsl", "include cycle"),
        ("noversion.glsl", "#version"),
        ("missing.glsl", "nope.glsl"),
    ],
)
def test_malformed_sources_raise_clear_errors(name, message):
    with pytest.raises(ShaderSourceError, match=message):
        preprocess(name, "VERTEX_SHADER", read)


def test_unknown_stage_is_refused():
    with pytest.raises(ShaderSourceError, match="unknown stage"):
        preprocess("prog.glsl", "TESSELLATION", read)


def test_every_shipped_program_preprocesses():
    from envstudio.resources import shader_root

    programs = [
        p
        for p in shader_root().rglob("*.glsl")
        if read_shader(str(p.relative_to(shader_root()))).startswith("#version")
    ]
    assert programs, "no shader programs found"
    for path in programs:
        name = str(path.relative_to(shader_root()))
        for stage in stages_in(read_shader(name)):
            source, _ = preprocess(name, stage, read_shader)
            assert "#include" not in source.replace("already included", "")
