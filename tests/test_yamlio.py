"""inputs/yamlio parses with libyaml when PyYAML has it: the same data, marks and errors as its Python parser.

libyaml's scanner and parser (C) feed the same Python composer, checks and constructor; a text either
one refuses is read again by the Python parser, so users see its messages and places.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import _require
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from thymio_bt.errors import UserError
from thymio_bt.inputs import yamlio

ROOT = Path(__file__).resolve().parents[1]
FILES = sorted(
    str(p.relative_to(ROOT))
    for folder in ("missions", "mazes", "assignments", "examples", "tests", "thymio_bt")
    for p in (ROOT / folder).rglob("*.y*ml")
)
#: characters that matter to YAML, and a few it does not allow
YAML_CHARS = list(" :-[]{},&*!|>'\"#%@`?\n\t\\.0123456789abcxyz_$/<") + ["\x00", "\x07", "\ufeff", "\u2028", "é"]

pytestmark = pytest.mark.skipif(  # in CI (THYMIO_BT_REQUIRE_ALL=1) a PyYAML without libyaml fails instead
    not yaml.__with_libyaml__ and not _require.REQUIRE_ALL, reason="PyYAML without libyaml"
)


def _marked(data: Any) -> Any:
    """``data`` with every mark it carries, for a comparison that sees them all."""
    if isinstance(data, yamlio.MarkedDict):
        items = {key: _marked(value) for key, value in data.items()}
        return "map", data.mark, dict(data.marks), dict(data.value_marks), items
    if isinstance(data, yamlio.MarkedList):
        return "seq", data.mark, list(data.marks), [_marked(value) for value in data]
    return type(data).__name__, repr(data)


def _outcome(text: str) -> Any:
    """What parsing ``text`` gives: its data and marks, or the error's message."""
    try:
        return _marked(yamlio._parse(text, "f.yaml"))
    except UserError as exc:
        return str(exc)


def _both(text: str, monkeypatch: pytest.MonkeyPatch) -> tuple[Any, Any]:
    """(the outcome with libyaml, the outcome with the Python parser alone)."""
    fast = _outcome(text)
    with monkeypatch.context() as patch:
        patch.setattr(yamlio, "_FastLoader", None)
        return fast, _outcome(text)


def test_a_valid_file_is_parsed_by_libyaml_alone(monkeypatch):
    text = (ROOT / "missions/maze_part1_2.yaml").read_text()
    expected = _outcome(text)
    monkeypatch.setattr(yamlio, "_Loader", None)  # the Python parser, were it used, would fail here
    assert _outcome(text) == expected


@pytest.mark.parametrize("path", FILES)
def test_libyaml_reads_every_file_as_the_python_parser_does(path, monkeypatch):
    fast, python = _both((ROOT / path).read_text(encoding="utf-8", errors="replace"), monkeypatch)
    assert fast == python


@settings(
    derandomize=True,
    database=None,
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    path=st.sampled_from([f for f in FILES if f.startswith(("missions", "mazes"))]),
    cut=st.integers(0, 5000),
    insert=st.text(alphabet=st.sampled_from(YAML_CHARS), max_size=6),
    drop=st.integers(0, 3),
)
def test_an_edited_file_parses_or_fails_as_with_the_python_parser(path, cut, insert, drop, monkeypatch):
    text = (ROOT / path).read_text(encoding="utf-8")
    cut %= len(text) + 1
    fast, python = _both(text[:cut] + insert + text[cut + drop :], monkeypatch)
    assert fast == python


def test_a_text_read_once_is_not_copied_and_one_read_again_is_kept_apart_from_its_callers(monkeypatch):
    copies: list[object] = []
    real_deepcopy = yamlio.copy.deepcopy
    monkeypatch.setattr(yamlio.copy, "deepcopy", lambda data: copies.append(data) or real_deepcopy(data))
    text = "root:\n  seq: [a, b]\n# a text no other test reads\n"
    first = yamlio.loads_yaml(text, "once.yaml")
    assert copies == []  # one read: the parse itself, never copied
    first["root"]["seq"].append("changed by the first caller")
    second = yamlio.loads_yaml(text, "once.yaml")
    assert second == {"root": {"seq": ["a", "b"]}}
    second["root"]["seq"].append("changed by the second caller")
    third = yamlio.loads_yaml(text, "once.yaml")
    assert third == {"root": {"seq": ["a", "b"]}} and len(copies) == 2
    assert yamlio.loads_yaml(text, "other.yaml") == {"root": {"seq": ["a", "b"]}}  # its own file name


def test_the_texts_read_are_remembered_by_hash_and_at_most_kept_texts_of_them():
    for i in range(yamlio.KEPT_TEXTS + 5):
        yamlio.loads_yaml(f"n: {i}\n", "many.yaml")
    assert len(yamlio._READ_ONCE) <= yamlio.KEPT_TEXTS
    assert all(isinstance(key, int) for key in yamlio._READ_ONCE)
