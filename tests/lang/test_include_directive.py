"""The #include directive (docs/assumptions.md (Assembler): "#include accepts `file`, `"file"` or
`<file>`", "nesting limit 32"): a directive without a file name or without its closing quote, and an
include one level too deep, are errors at the directive."""
from __future__ import annotations

import pytest

from opentmcl.lang.assembler import MAX_INCLUDE_DEPTH, AsmError, assemble, assemble_file


def _error(src: str, **kw) -> AsmError:
    with pytest.raises(AsmError) as err:
        assemble(src, **kw)
    return err.value


@pytest.mark.parametrize("line", ["#include", '#include ""', "#include <>", "#include // no name"])
def test_include_without_a_file_name(line):
    """docs/assumptions.md (Assembler): "#include accepts `file`, `"file"` or `<file>`" - each
    form without a name is an error naming the expected form."""
    e = _error(line)
    assert (e.line, e.column, e.message) == (1, 1, "expected a file name: #include <file>")


@pytest.mark.parametrize(("line", "close", "col"), [('#include "TMCLParam.tmc', '"', 1),
                                                    ("   #include <TMCLParam.tmc", ">", 4)])
def test_an_include_name_without_its_closing_quote_is_an_error_at_the_directive(line, close, col):
    """docs/assumptions.md (Assembler): "#include accepts `file`, `"file"` or `<file>`"; an opening
    quote or < without its partner is an AsmError at the '#' (file:line:column), with the closed
    form as the last valid spelling."""
    assert assemble(f'{line}{close}\nSAP APMaxPositioningSpeed, 0, 1').instructions[0] == (5, 4, 0, 1)
    e = _error(f"MST 0\n{line}\nMST 1")
    assert (e.file, e.line, e.column, e.message) == ("<source>", 2, col, f"missing closing {close} in #include")
    assert str(e) == f"<source>:2:{col}: missing closing {close} in #include"


def test_an_include_one_level_too_deep_is_an_error_at_its_directive(tmp_path):
    """docs/assumptions.md "#include": "32 include files nested inside each other are read, the
    33rd `#include` is refused" - on its own line, at the column of its '#'."""
    assert MAX_INCLUDE_DEPTH == 32

    def chain(depth: int):
        for i in range(1, depth + 1):
            body = f"   #include f{i + 1}.inc\n" if i < depth else "Deepest = 1\n"
            (tmp_path / f"f{i}.inc").write_text(f"// level {i}\n{body}")
        (tmp_path / "main.tmc").write_text("#include f1.inc\nMVP ABS, 0, Deepest\n")
        return tmp_path / "main.tmc"

    assert assemble_file(chain(32)).instructions[0] == (4, 0, 0, 1)
    with pytest.raises(AsmError) as info:
        assemble_file(chain(33))
    e = info.value
    assert e.file.endswith("f32.inc")
    assert (e.line, e.column, e.message) == (2, 4, "includes nested deeper than 32")
    assert str(e.errors[0]).endswith("f32.inc:2:4: includes nested deeper than 32")
