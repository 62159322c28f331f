"""BT.CPP 4's script language here and in BT.CPP itself (behaviortreepy, BT.CPP 4.8.2): a table of
what BT.CPP does, quirks included, and thousands of generated scripts and conditions compared."""

import random
from xml.sax.saxutils import quoteattr

import pytest
from _require import module

from thymio_bt.btcpp.runtime.script import ScriptError, parse
from thymio_bt.btcpp.runtime.values import text, truth

PRELUDE = "s := 'w'; n := 4; f := 2.5; "

#: script -> the entry x as BT.CPP's get_string gives it, "error" (fails as it runs) or "parse"
#: (refused when the tree is made); every row was run in behaviortreepy
BTCPP = {
    "x := 1 - 2 + 3": "-4.000000",  # + - and * / are evaluated right to left
    "x := 10 / 5 * 2": "1.000000",
    "x := 16 / 4 / 2 / 2": "4.000000",
    "x := 1 | 2 ^ 3": "0.000000",  # bitwise and logic: left to right
    "x := 1 || 1 && 0": "0.000000",
    "x := 7 / 2": "3.500000",
    "x := 1 / 0": "inf",
    "x := 0 / 0": "-nan",
    "x := '3' + '4'": "34",
    "x := '3' + 1": "error",
    "x := -'3'": "error",
    "x := 'a' .. 2.5": "a2.500000",
    "x := 'a' .. 3": "a3",
    "x := 'a' .. true": "a1",
    "x := 1 .. 2": "error",
    "x := 1 + 2 .. 'a'": "parse",  # arithmetic, bitwise and .. do not mix without parentheses
    "x := -1 .. 'a'": "parse",
    "x := !false + 0": "parse",
    "x := 1 + 1 == 2 && 'a' .. 'b' == 'ab'": "parse",
    "x := 1 + (1 & 1)": "2.000000",
    "x := 1 ? 1 & 1 : 2 + 2": "1.000000",
    "x := 1 ? 2 : 3 ? 4 : 5": "parse",
    "x := y := 3": "parse",
    "x := (y := 3) + 1": "4.000000",
    "x := 1;": "parse",
    "x := .5": "parse",
    "x := 5.": "parse",
    "x := 1e400": "parse",
    "x := 9223372036854775808": "parse",
    "x := 9223372036854775807 + 0": "error",
    "x := true": "1",
    "x := 2 * true": "2.000000",
    "x := 2 && 1": "error",
    "x := 1 && 0.5": "1.000000",
    "x := 1 && -0.5": "error",
    "x := false && y": "error",  # both sides are evaluated
    "x := !2": "0.000000",
    "x := ~2.5": "-3.000000",
    "x := ~(1/0)": "error",
    "x := 3 & 1.5": "error",
    "x := 1 == 1.00000001": "1.000000",
    "x := (0/0) < 0": "1.000000",
    "x := (0/0) == (0/0)": "0.000000",
    "x := 'b' < 'ab'": "0.000000",
    "x := '3abc' == 3": "1.000000",
    "x := 'true' == 1": "1.000000",
    "x := 'a' < 1": "error",
    "x := 1 < 2 == 1": "0.000000",
    "x := 1 ? 2 : 3": "2",
    "x := '1' ? 1 : 2": "1",
    "x := 'x' ? 1 : 2": "error",
    "n := 4; n /= 3; x := n": "error",  # a whole-number entry stays whole
    "n := 4; n = 2.0; x := n": "2",
    "n := 4; n = 'true'; x := n": "1.000000",
    "n := 4; n += '1'; x := n": "error",
    "s := 'a'; s += 'b'; x := s": "ab",
    "s := 'a'; s += 1; x := s": "error",
    "s := 'a'; s = 4; x := s": "error",
    "x := y": "error",
    "y = 1": "error",
    "x := 0x7fffffffffffffff": "9223372036854775807",
    "x := +1": "1",
}


def ours(code: str, keys=("x",)) -> tuple:
    """Our outcome as BT.CPP's is read: ("parse",), ("error",) or ("ok", x...) as strings."""
    try:
        script = parse(code)
    except ScriptError:
        return ("parse",)
    board: dict = {}
    try:
        script(board)
    except ScriptError:
        return ("error",)
    return ("ok", *(None if board.get(k) is None else text(board[k]) for k in keys))


def btcpp(bt, code: str, keys=("x",)) -> tuple:
    """BT.CPP's outcome of a ``Script`` node running ``code`` on an empty blackboard."""
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="M"><Script code={quoteattr(code)}/></BehaviorTree></root>'
    try:
        tree = bt.BehaviorTreeFactory().create_tree_from_text(xml)
    except Exception:  # BT.CPP's exceptions arrive as RuntimeError, IndexError (stod)...
        return ("parse",)
    try:
        tree.tick_once()
    except Exception:  # BT.CPP's exceptions arrive as RuntimeError, IndexError (stod)...
        return ("error",)
    board, values = tree.root_blackboard(), []
    for key in keys:
        try:
            values.append(board.get_string(key))
        except Exception:  # BT.CPP's exceptions arrive as RuntimeError, IndexError (stod)...
            values.append(None)
    return ("ok", *values)


@pytest.mark.parametrize("code, expected", BTCPP.items())
def test_a_script_does_what_btcpp_does(code, expected):
    assert ours(code) == ((expected,) if expected in ("error", "parse") else ("ok", expected))


def test_a_condition_is_0_or_1_or_a_double_not_below_0():
    assert [truth(v) for v in (0, 1, 0.0, 0.5, 2.0)] == [False, True, False, True, True]
    for value in (2, -1, -0.5, "1", None):
        with pytest.raises(ScriptError):
            truth(value)


ATOMS = ["1", "2", "0", "3.5", "0.5", "1e3", "0x1F", "7", "'3'", "'a'", "''", "' 4'", "'2x'", "'true'"]
ATOMS += ['"q"', "true", "false", "y", "s", "n", "f", "+1"]
OPERATORS = ["+", "-", "*", "/", "..", "&&", "||", "&", "|", "^", "==", "!=", "<", ">=", "<=", ">"]
TARGETS = ["s", "n", "f", "x", "z"]
ASSIGNMENTS = [":=", "=", "+=", "-=", "*=", "/="]


def _expression(rng: random.Random, depth: int = 0) -> str:
    roll = rng.random()
    if depth > 3 or roll < 0.3:
        return rng.choice(ATOMS)
    if roll < 0.42:
        return rng.choice(["-", "!", "~", "- "]) + _expression(rng, depth + 1)
    if roll < 0.55:
        return f"({_expression(rng, depth + 1)})"
    if roll < 0.6:
        return " ? ".join(
            [_expression(rng, depth + 1), f"{_expression(rng, depth + 1)} : {_expression(rng, depth + 1)}"]
        )
    if roll < 0.63:
        return f"({rng.choice(TARGETS)} {rng.choice(ASSIGNMENTS)} {_expression(rng, depth + 1)})"
    return f"{_expression(rng, depth + 1)} {rng.choice(OPERATORS)} {_expression(rng, depth + 1)}"


def _script(rng: random.Random) -> str:
    statements = []
    for _ in range(rng.randint(1, 3)):
        if rng.random() < 0.6:
            statements.append(f"x := {_expression(rng)}")
        else:
            target = rng.choice(TARGETS)
            statements.append(f"{target} {rng.choice(ASSIGNMENTS)} {_expression(rng)}; x := {target}")
    return PRELUDE + "; ".join(statements)


def test_the_table_is_btcpp_s():
    bt = module("behaviortreepy")
    assert {code: btcpp(bt, code) for code in BTCPP} == {code: ours(code) for code in BTCPP}


def test_generated_scripts_end_with_the_same_entries_and_conditions_the_same_status():
    """4000 scripts over numbers, strings, entries and every operator, and 4000 expressions as a
    ``ScriptCondition``: the same entries (or the same error) and the same status as BT.CPP."""
    bt = module("behaviortreepy")
    rng = random.Random(0)
    keys = ("x", *TARGETS)
    scripts = [_script(rng) for _ in range(4000)]
    differ = [code for code in scripts if btcpp(bt, code, keys) != ours(code, keys)]
    assert differ == []
    conditions = [_expression(rng) for _ in range(4000)]
    differ = [code for code in conditions if _btcpp_condition(bt, code) != _our_condition(code)]
    assert differ == []


def _btcpp_condition(bt, code: str) -> str:
    xml = f'<root BTCPP_format="4"><BehaviorTree ID="M"><ScriptCondition code={quoteattr(code)}/></BehaviorTree></root>'
    try:
        tree = bt.BehaviorTreeFactory().create_tree_from_text(xml)
    except Exception:  # BT.CPP's exceptions arrive as RuntimeError, IndexError (stod)...
        return "parse"
    try:
        return tree.tick_once().name
    except Exception:  # BT.CPP's exceptions arrive as RuntimeError, IndexError (stod)...
        return "error"


def _our_condition(code: str) -> str:
    try:
        script = parse(code)
    except ScriptError:
        return "parse"
    try:
        return "SUCCESS" if truth(script({})) else "FAILURE"
    except ScriptError:
        return "error"
