"""Fuzzing: whatever text a student writes, the loaders answer with a UserError, never a crash.

Arbitrary text and mutations of the real missions, libraries and mazes (lines deleted, duplicated
or swapped, characters edited, values replaced by nasty ones) go through the YAML loader, the
mission loader and the maze loader; any exception but :class:`UserError` is a bug. The unit parser
may raise only :class:`UnitError` (the ``ValueError`` its API documents). Runs are derandomized, so
CI sees the same examples every time.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Callable
from datetime import timedelta
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from thymio_bt.errors import UserError
from thymio_bt.inputs.units import SI_UNIT, UNITS, Quantity, UnitError, parse_value
from thymio_bt.inputs.yamlio import loads_yaml
from thymio_bt.maze import load_maze
from thymio_bt.mission import load_mission

ROOT = Path(__file__).resolve().parents[1]

FUZZ = settings(
    derandomize=True,
    deadline=timedelta(seconds=2),
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)


def fuzz(examples: int) -> settings:
    """Deterministic settings; the deadline catches a hang (a load takes ~10 ms)."""
    return settings(FUZZ, max_examples=examples)


#: Characters that matter to YAML, plus a few that are not allowed in it at all.
YAML_CHARS = list(" :-[]{},&*!|>'\"#%@`?\n\t\\.0123456789abcdefxyz_$/") + ["\x00", "\x07", "\ufeff", "\u2028", "é"]

#: Values a student (or a cat on the keyboard) might write where a value goes.
NASTY_VALUES = [
    "",
    "~",
    "null",
    "true",
    "no",
    "-1",
    "0",
    "1e999",
    "-1e999",
    ".nan",
    ".inf",
    "9" * 5000,
    "0x1F",
    "0o17",
    "2020-02-30",
    "12:30:00",
    "[1, 2]",
    "{a: 1}",
    "[]",
    "{}",
    "[0.5, 0.3]",
    "[0.5, 0.3, pi/2, 1]",
    "[x, y, z]",
    "pi/",
    "5 parsecs",
    "5cm + 90deg",
    "2cm*3cm",
    "1/0",
    "((((1)))",
    ")",
    "-" * 100 + "1",
    "(" * 100 + "1",
    "$nope",
    "$",
    "bb:",
    "bb:turn_angle",
    "*undefined",
    "&a x",
    "!!python/object/apply:os.system ['true']",
    "!!int abc",
    "!!float x",
    "!!binary ===",
    "!!timestamp nope",
    "!!set {a}",
    "!unknown x",
    "|",
    ">",
    "'unterminated",
    '"\\x00"',
    '"\\u0007"',
    "part9",
    "thymio",
    "forever",
    "success_on_one",
    "lib/maze_legs.yaml",
    "../mazes/two_parts_maze.yaml",
    "/",
    "..",
    ".",
    "-90deg",
    "360deg",
    "1e-400",
    "5 cm/s",
    "10 Hz",
    "90°",
]

#: File to mutate (relative to the checkout) -> how to load after mutating it.
TARGETS: dict[str, tuple[str, str]] = {
    **{f"missions/{p.name}": ("mission", f"missions/{p.name}") for p in sorted((ROOT / "missions").glob("*.yaml"))},
    "missions/lib/maze_legs.yaml": ("mission", "missions/maze_part1_2.yaml"),
    "missions/lib/navigation.yaml": ("mission", "missions/waypoints_obstacles.yaml"),
    "mazes/two_parts_maze.yaml": ("maze", "mazes/two_parts_maze.yaml"),
    "mazes/arena.yaml": ("maze", "mazes/arena.yaml"),
}


@pytest.fixture(scope="module")
def sandbox(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A copy of missions/ and mazes/ whose files the mutations overwrite (then restore)."""
    root = tmp_path_factory.mktemp("fuzz")
    for folder in ("missions", "mazes"):
        shutil.copytree(ROOT / folder, root / folder)
    return root


def must_not_crash(load: Callable[[], object]) -> None:
    """Call ``load``; it may succeed or raise UserError with usable problems, nothing else."""
    try:
        load()
    except UserError as exc:
        assert exc.problems, "a UserError without problems"
        for problem in exc.problems:
            assert problem.message.strip() and problem.line >= 0 and problem.column >= 0
            str(problem)


def load_target(sandbox: Path, target: str) -> None:
    kind, entry = TARGETS[target]
    path = sandbox / entry
    must_not_crash(lambda: load_mission(path) if kind == "mission" else load_maze(path))


# ------------------------------------------------------------------------------------- arbitrary text


@fuzz(250)
@given(st.one_of(st.text(), st.text(alphabet=st.sampled_from(YAML_CHARS), max_size=200)))
def test_yaml_loader_on_arbitrary_text(text: str) -> None:
    must_not_crash(lambda: loads_yaml(text, "fuzz.yaml"))


@fuzz(120)
@given(st.text(alphabet=st.sampled_from(YAML_CHARS), max_size=300))
def test_mission_loader_on_arbitrary_text(sandbox: Path, text: str) -> None:
    path = sandbox / "missions" / "fuzz.yaml"
    path.write_text(text, encoding="utf-8")
    must_not_crash(lambda: load_mission(path))


# ------------------------------------------------------------------------------------- mutations


def _mutate(lines: list[str], data: st.DataObject) -> list[str]:
    lines = list(lines)
    for _ in range(data.draw(st.integers(1, 3), label="edits")):
        if not lines:
            lines = [""]
        i = data.draw(st.integers(0, len(lines) - 1), label="line")
        edit = data.draw(st.sampled_from(["delete", "duplicate", "swap", "char", "value", "indent"]), label="edit")
        if edit == "delete":
            del lines[i]
        elif edit == "duplicate":
            lines.insert(i, lines[i])
        elif edit == "swap":
            j = data.draw(st.integers(0, len(lines) - 1), label="other line")
            lines[i], lines[j] = lines[j], lines[i]
        elif edit == "char":
            line = lines[i]
            pos = data.draw(st.integers(0, len(line)), label="column")
            new = data.draw(st.sampled_from(YAML_CHARS), label="character")
            cut = data.draw(st.integers(0, 1), label="replace")
            lines[i] = line[:pos] + new + line[pos + cut :]
        elif edit == "value":
            line = lines[i]
            if ":" in line:
                key, _, _ = line.partition(":")
                lines[i] = f"{key}: {data.draw(st.sampled_from(NASTY_VALUES), label='value')}"
        else:
            lines[i] = data.draw(st.sampled_from(["", " ", "  ", "\t", "- "]), label="indent") + lines[i]
    return lines


@fuzz(600)
@given(target=st.sampled_from(sorted(TARGETS)), data=st.data())
def test_loaders_on_mutated_real_files(sandbox: Path, target: str, data: st.DataObject) -> None:
    original = (ROOT / target).read_text(encoding="utf-8")
    mutated = "\n".join(_mutate(original.split("\n"), data))
    path = sandbox / target
    path.write_text(mutated, encoding="utf-8")
    try:
        load_target(sandbox, target)
    finally:
        path.write_text(original, encoding="utf-8")


@fuzz(250)
@given(
    target=st.sampled_from([t for t in sorted(TARGETS) if TARGETS[t][0] == "mission"]),
    value=st.sampled_from(NASTY_VALUES),
    data=st.data(),
)
def test_every_value_of_a_mission_replaced_by_a_nasty_one(
    sandbox: Path, target: str, value: str, data: st.DataObject
) -> None:
    original = (ROOT / target).read_text(encoding="utf-8")
    places = [i for i, line in enumerate(original.split("\n")) if ":" in line and not line.lstrip().startswith("#")]
    i = data.draw(st.sampled_from(places), label="line")
    lines = original.split("\n")
    key = lines[i].partition(":")[0]
    # inside a flow mapping ({a: 1, b: 2}) replace one entry's value; else the whole value
    if "{" in lines[i] and "," in lines[i]:
        head, _, tail = lines[i].partition(",")
        lines[i] = f"{head.rpartition(':')[0]}: {value}, {tail}" if ":" in head else lines[i]
    else:
        lines[i] = f"{key}: {value}"
    path = sandbox / target
    path.write_text("\n".join(lines), encoding="utf-8")
    try:
        load_target(sandbox, target)
    finally:
        path.write_text(original, encoding="utf-8")


_OVERRIDE_NAMES = [
    "cruise",
    "final_stop",
    "tick_hz",
    "time_limit",
    "seed",
    "noise.wheel",
    "noise.range_sd",
    "noise.x",
    "noise.",
    "nope",
    "",
]
_TEXT_OR_NASTY = st.sampled_from(NASTY_VALUES) | st.text(max_size=20)


@fuzz(150)
@given(
    overrides=st.dictionaries(st.sampled_from(_OVERRIDE_NAMES) | st.text(max_size=8), _TEXT_OR_NASTY, max_size=3),
    start=st.none() | _TEXT_OR_NASTY,
    maze=st.none() | st.sampled_from(["../mazes/arena.yaml", "arena", "nope", "", "/", "\0", "missions"]),
)
def test_mission_loader_with_arbitrary_command_line_values(
    overrides: dict[str, str], start: str | None, maze: str | None
) -> None:
    # what --set NAME=VALUE, --start X,Y,YAW and --maze FILE pass to the loader
    must_not_crash(
        lambda: load_mission(ROOT / "missions" / "maze_part1_2.yaml", overrides=overrides, start=start, maze=maze)
    )


def test_the_sandbox_loads_the_unmutated_files(sandbox: Path) -> None:
    # so that the fuzz tests above exercise the whole loader, not only its first error
    for target in TARGETS:
        kind, entry = TARGETS[target]
        (load_mission if kind == "mission" else load_maze)(sandbox / entry)


# ------------------------------------------------------------------------------------- units

_TOKENS = [
    *UNITS,
    "pi",
    "$side",
    "$zero",
    "$nope",
    "+",
    "-",
    "*",
    "/",
    "(",
    ")",
    " ",
    "1",
    "0",
    "2.5",
    ".5",
    "1e3",
    "1e999",
    "e",
    "x",
    "°",
    "/s",
    "1.",
    "m/",
    "--",
]


def _resolve(name: str) -> Quantity:
    known = {"side": Quantity(0.15, "length"), "zero": Quantity(0.0)}
    if name not in known:
        raise KeyError(name)
    return known[name]


def _check_parse(text: str) -> None:
    for resolve in (None, _resolve):
        try:
            quantity = parse_value(text, resolve)
        except UnitError as exc:
            assert str(exc)
            continue
        assert math.isfinite(quantity.value) and (quantity.kind is None or quantity.kind in SI_UNIT)


@fuzz(400)
@given(st.one_of(st.text(max_size=60), st.lists(st.sampled_from(_TOKENS), max_size=12).map("".join)))
def test_parse_value_raises_only_unit_errors(text: str) -> None:
    _check_parse(text)


@pytest.mark.parametrize(
    "text",
    [
        "(" * 10_000 + "1" + ")" * 10_000,
        "-" * 100_000 + "1",
        "1" * 100_000,
        "1e308*1e308",
        "1e308*1e308-1e308*1e308",
        "1/1e-400",
        "$" + "a" * 10_000,
    ],
)
def test_parse_value_survives_pathological_text(text: str) -> None:
    _check_parse(text)


@fuzz(100)
@given(st.floats(allow_nan=True, allow_infinity=True) | st.integers() | st.booleans())
def test_parse_value_of_numbers_is_finite_or_an_error(number: float | int | bool) -> None:
    try:
        quantity = parse_value(number)
    except UnitError:
        assert isinstance(number, bool) or not math.isfinite(number)
    else:
        assert quantity.value == float(number) and quantity.kind is None
