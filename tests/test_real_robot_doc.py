"""docs/real_robot.md is a guide a student follows on the day they get a robot: its sections come in
the order of that day, and every command line it gives is one the real CLI takes, with backends and
backend options that exist."""

import re
import shlex
from pathlib import Path

import click
import pytest

from thymio_bt.backends import backend_kind
from thymio_bt.cli import main
from thymio_bt.cli.app import parse_overrides
from thymio_bt.mission import load_mission

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "real_robot.md"

#: what the day's sections are about, in their order (a heading matches the first pattern it contains)
ORDER = ("backend", "install", "connect", "calibrat", "first run", "expect", "differ", "appendix")


def headings(text: str) -> list[str]:
    return re.findall(r"^## (.+)$", text, re.M)


def command_lines(text: str) -> list[list[str]]:
    """The ``thymio-bt`` command lines of the guide's shell blocks, split as a shell would."""
    lines = []
    for block in re.findall(r"```(?:bash|sh|shell)\n(.*?)```", text, re.S):
        for line in block.splitlines():
            words = shlex.split(line, comments=True)
            if words and words[-1] == "&":
                words.pop()
            if words and words[0] == "thymio-bt":
                lines.append(words[1:])
    return lines


def parse(words: list[str]) -> click.Context:
    """Parse ``words`` as the CLI does (subcommands, options, their values): a mistake raises."""
    command: click.Command = main
    rest = list(words)
    name = "thymio-bt"
    while isinstance(command, click.Group):
        assert rest, f"'{name}' needs a subcommand"
        name = rest.pop(0)
        found = command.get_command(click.Context(command), name)
        assert found is not None, f"'{name}' is not a command"
        command = found
    return command.make_context(name, rest)


def test_the_sections_follow_the_day_a_student_gets_a_robot():
    titles = [t.lower() for t in headings(GUIDE.read_text())]
    first = {}
    for i, title in enumerate(titles):
        topic = next((t for t in ORDER if t in title), None)
        if topic is not None:
            first.setdefault(topic, i)
    assert list(first) == list(ORDER), titles  # each topic has a section, in the day's order
    appendices = [t for t in titles if t.startswith("appendix")]
    assert appendices and titles[-len(appendices) :] == appendices  # the measurements come last


def test_the_guide_says_the_cli_not_python_for_the_robots_constants():
    text = GUIDE.read_text()
    assert "RealConfig(" not in text and "thymio-bt calibrate --backend aseba" in text


GUIDE_COMMANDS = command_lines(GUIDE.read_text())


def test_the_guide_has_commands():
    assert len(GUIDE_COMMANDS) >= 8


@pytest.mark.parametrize("words", GUIDE_COMMANDS, ids=" ".join)
def test_each_command_line_is_one_the_cli_takes(words, monkeypatch):
    monkeypatch.chdir(ROOT)  # missions/... as the guide writes them
    parse(words)
    for option, value in zip(words, words[1:], strict=False):
        if option == "--backend":
            backend_kind(value)  # a UserError for a backend that does not exist
    backend = words[words.index("--backend") + 1] if "--backend" in words else "sim"
    opts = dict(v.split("=", 1) for o, v in zip(words, words[1:], strict=False) if o == "--backend-opt")
    backend_kind(backend).parse_options(opts)  # a UserError for an option it does not have
    if words[0] == "run" and Path(words[1]).exists():  # its --set names and values, on the mission
        sets = tuple(v for o, v in zip(words, words[1:], strict=False) if o == "--set")
        load_mission(words[1], parse_overrides(sets), run_plugins=False)


def test_a_backend_the_cli_calls_untested_is_called_untested_in_the_guide():
    text = GUIDE.read_text()
    named = set(re.findall(r"--backend (\w+)", text))
    for name in named:
        if "untested" in backend_kind(name).summary:
            assert re.search(rf"`{name}`[^\n]*\*\*Untested here\*\*|{name}` \(untested\)", text), name
