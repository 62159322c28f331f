"""No function in thymio_bt/ of radon grade D or worse (cyclomatic complexity above 20, counting
boolean operators, comprehensions and conditional expressions as ``radon cc`` does): a function
that needs more is split into named steps (docs/development.md)."""

from collections.abc import Iterator
from pathlib import Path

from radon.complexity import cc_rank, cc_visit
from radon.visitors import Function

ROOT = Path(__file__).resolve().parents[1]
#: the most a function may have: radon's grade C ends here, D (21-30) begins above
MOST = 20


def _functions(blocks: list) -> Iterator[Function]:
    """The functions and methods of radon's blocks, and the functions defined inside them."""
    for block in blocks:
        if isinstance(block, Function):
            yield block
            yield from _functions(block.closures)


def too_complex(source: str, file: str) -> list[str]:
    """``file:line name complexity (grade)`` of each function in ``source`` above :data:`MOST`."""
    return [
        f"{file}:{f.lineno} {f.fullname} {f.complexity} ({cc_rank(f.complexity)})"
        for f in _functions(cc_visit(source))
        if f.complexity > MOST
    ]


def test_no_function_of_grade_d_or_worse():
    found = [
        line
        for path in sorted((ROOT / "thymio_bt").rglob("*.py"))
        for line in too_complex(path.read_text(), str(path.relative_to(ROOT)))
    ]
    assert not found, "split these into named steps (radon grade C at most, complexity <= 20):\n" + "\n".join(found)


def test_the_check_names_a_function_just_over_the_line_and_spares_one_on_it():
    """21 paths is grade D (named with its file and line, inside a class or a function too), 20 is C."""

    def function(name: str, branches: int, indent: str = "") -> str:
        body = "".join(f"{indent}    if x == {i}:\n{indent}        return {i}\n" for i in range(branches))
        return f"{indent}def {name}(x):\n{body}{indent}    return -1\n"

    source = (
        function("on_the_line", 19)
        + function("over", 20)
        + "class Holder:\n"
        + function("method", 20, "    ")
        + "def outer():\n"
        + function("inner", 20, "    ")
        + "    return inner\n"
    )
    assert too_complex(source, "m.py") == [
        "m.py:41 over 21 (D)",
        "m.py:127 inner 21 (D)",
        "m.py:84 Holder.method 21 (D)",
    ]
