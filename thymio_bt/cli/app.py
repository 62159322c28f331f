"""The ``thymio-bt`` command group and what its commands share: the error exit, option types and parsers.

The commands themselves live in the modules of :mod:`thymio_bt.cli` named for what they do; a
command's module is imported, and registers its commands on :func:`main`, only when one of them is
asked for (:data:`COMMANDS`). Heavy imports stay inside the commands.

Example::

    >>> parse_pairs(("device=/dev/ttyACM0", " port = 33333 "), "--backend-opt", "device=/dev/ttyACM0")
    {'device': '/dev/ttyACM0', 'port': '33333'}
    >>> POSITIVE.convert("0.5", None, None)
    0.5
"""

from __future__ import annotations

import importlib
import json
import math
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn, TypeVar

import click

from thymio_bt.errors import UserError

F = TypeVar("F", bound=Callable[..., Any])


def fail(exc: UserError) -> NoReturn:
    """Print each problem of ``exc`` as one ``error:`` line on stderr and exit 2 (a user error)."""
    for problem in exc.problems:
        click.echo(f"error: {problem}", err=True)
    if len(exc.problems) > 1:
        click.echo(f"{len(exc.problems)} problems", err=True)
    sys.exit(2)


class _Positive(click.ParamType):
    """A finite number > 0 (click's FloatRange lets NaN through: every comparison with it is false)."""

    name = "number"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        """``value`` as a float, or click's usage error (exit 2) when it is not a finite number > 0."""
        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(f"{value!r} is not a number", param, ctx)
        if not (math.isfinite(number) and 0 < number <= 1e9):
            self.fail(f"{value} must be a finite number > 0", param, ctx)
        return number


#: the option type of speed-ups, factors and sizes: a finite number > 0
POSITIVE = _Positive()


def parse_overrides(values: tuple[str, ...]) -> dict[str, str]:
    """The ``--set NAME=VALUE`` options as a dict of mission overrides.

    >>> parse_overrides(("cruise=0.15", "noise.wheel=0.03"))
    {'cruise': '0.15', 'noise.wheel': '0.03'}
    >>> parse_overrides(("cruise",))
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: --set expects NAME=VALUE, got 'cruise' (hint: --set cruise=0.15)
    """
    return parse_pairs(values, "--set", "cruise=0.15")


def parse_pairs(values: tuple[str, ...], option: str, example: str) -> dict[str, str]:
    """``NAME=VALUE`` arguments of a repeatable option, as a dict (``example`` goes in the hint)."""
    out = {}
    for item in values:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise UserError(f"{option} expects NAME=VALUE, got '{item}' (hint: {option} {example})")
        out[name.strip()] = value.strip()
    return out


def pose_text(pose: dict[str, float] | None) -> str:
    """A report's or log's pose as the summaries print it.

    >>> pose_text({"x": 0.45, "y": 0.3, "yaw": 1.5707963}), pose_text(None)
    ('x=0.4500 m  y=0.3000 m  yaw=90.00 deg', 'no robot')
    """
    if not pose:
        return "no robot"
    return f"x={pose['x']:.4f} m  y={pose['y']:.4f} m  yaw={math.degrees(pose['yaw']):.2f} deg"


def clearance_text(gap: float | None) -> str:
    """The summary's min clearance: in metres to 0.1 mm, a gap under that (not contact) to 1 µm, so
    that 0 means contact (a collision) and nothing else.

    >>> clearance_text(0.01537), clearance_text(3e-05), clearance_text(0.0), clearance_text(None)
    ('0.0154 m', '0.000030 m', '0.0000 m', 'n/a')
    """
    if gap is None:
        return "n/a"
    return f"{gap:.6f} m" if 0.0 < gap < 5e-5 else f"{gap:.4f} m"


def json_text(data: Any) -> str:
    """``data`` as the JSON the commands write: indented, strict (no NaN), with a final newline.

    >>> print(json_text({"status": "SUCCESS", "ticks": 3}), end="")
    {
     "status": "SUCCESS",
     "ticks": 3
    }
    """
    return json.dumps(data, indent=1, allow_nan=False) + "\n"


def not_both(first: str, second: str, given: bool, hint: str) -> None:
    """Refuse two options that exclude each other (``given``: both were), rather than quietly use one.

    >>> not_both("--workers", "--dask", False, "")
    >>> not_both("--workers", "--dask", True, "the cluster decides")
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: --workers and --dask exclude each other (hint: the cluster decides)
    """
    if given:
        raise UserError(f"{first} and {second} exclude each other (hint: {hint})")


def workers_or_dask(workers: int | None, dask: str | None) -> None:
    """``--workers`` is for a local pool, ``--dask`` for a cluster: not both."""
    hint = "the Dask cluster's workers run the work: drop --workers"
    not_both("--workers", "--dask", workers is not None and dask is not None, hint)


def path_option(*names: str, help: str, default: Any = None, **settings: Any) -> Callable[[F], F]:
    """An option that takes a file path (a :class:`~pathlib.Path`); ``settings`` go to :func:`click.option`."""
    return click.option(*names, type=click.Path(path_type=Path), default=default, help=help, **settings)


def mission_options(set_help: str, start_help: str) -> Callable[[F], F]:
    """The options that change the mission run (``--set``, ``--maze``, ``--start``), in that order."""
    options = (
        click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help=set_help),
        path_option("--maze", help="Run in another maze file."),
        click.option("--start", default=None, metavar="X,Y,YAW", help=start_help),
    )
    return _stacked(options)


def backend_options(backend_help: str, default: str | None = None) -> Callable[[F], F]:
    """Where a command reaches its robot: ``--backend NAME`` and ``--backend-opt KEY=VALUE``, in that order."""
    options = (
        click.option(
            "--backend", "backend", default=default, show_default=default is not None, metavar="NAME", help=backend_help
        ),
        click.option(
            "--backend-opt",
            "backend_opts",
            multiple=True,
            metavar="KEY=VALUE",
            help="A setting of the backend, e.g. --backend-opt device=/dev/ttyACM0 (repeatable; see "
            "'thymio-bt backends').",
        ),
    )
    return _stacked(options)


def _stacked(options: tuple[Callable[[F], F], ...]) -> Callable[[F], F]:
    """One decorator applying ``options`` so that ``--help`` lists them in the order given."""

    def apply(command: F) -> F:
        for option in reversed(options):
            command = option(command)
        return command

    return apply


def coverage_options(coverage_help: str) -> Callable[[F], F]:
    """The options that measure the tree's coverage (``--coverage``, ``--coverage-tree``), in that order."""
    options = (
        click.option("--coverage", is_flag=True, help=coverage_help),
        path_option(
            "--coverage-tree",
            metavar="FILE",
            help="Draw the tree with its coverage (.dot; .svg or .png need Graphviz's dot); implies --coverage.",
        ),
    )
    return _stacked(options)


def viewer_options(command: F) -> F:
    """The options of commands that show a run: ``--view`` and ``--speedup``, in that order."""
    command = click.option(
        "--speedup",
        type=POSITIVE,
        default=None,
        help="Speed-up of --view (default 1: real time) and --gif (default 4).",
    )(command)
    return click.option(
        "--view", is_flag=True, help="Watch the run in a window (pygame): SPACE pause, N step, +/- speed, Q quit."
    )(command)


#: the module of :mod:`thymio_bt.cli` that defines each command, imported when the command is asked
#: for: a command pays at start-up for its own module only (``run`` for neither asyncio nor the grader)
COMMANDS: dict[str, str] = {
    "backends": "inspection",
    "behaviours": "inspection",
    "calibrate": "calibrating",
    "check": "checking",
    "compare": "comparing",
    "export": "logs",
    "grade": "grading",
    "lint": "linting",
    "maze": "mazes",
    "palette": "inspection",
    "replay": "logs",
    "run": "running",
    "schema": "inspection",
    "serve": "serving",
    "sweep": "sweeps",
    "tree": "inspection",
    "validate": "inspection",
    "view": "viewing",
}


class _Commands(click.Group):
    """The command group, its commands' modules imported on demand (:data:`COMMANDS`); a Ctrl-C outside
    a run's own handling (or a second one) exits 130, quietly (143 when a SIGTERM came first)."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        """Every command's name, its module not imported."""
        return sorted({*self.commands, *COMMANDS})

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        """The command ``cmd_name``, its module imported first (it registers its commands on :func:`main`)."""
        if cmd_name not in self.commands and cmd_name in COMMANDS:
            importlib.import_module(f"thymio_bt.cli.{COMMANDS[cmd_name]}")
        return super().get_command(ctx, cmd_name)

    def invoke(self, ctx: click.Context) -> Any:
        """Run the command; a KeyboardInterrupt prints ``interrupted`` and exits 130 (or the code of
        the first signal of an :class:`~thymio_bt.run.interrupts.Interrupted`)."""
        try:
            return super().invoke(ctx)
        except KeyboardInterrupt as exc:
            click.echo("\ninterrupted", err=True)
            sys.exit(getattr(exc, "exit_code", 130))


@click.group(cls=_Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="thymio-bt")
@click.option(
    "--color",
    "--colour",
    "color",
    type=click.Choice(["auto", "always", "never"]),
    default="auto",
    show_default=True,
    help="Colour in the output; auto: on a terminal, unless NO_COLOR is set.",
)
@click.pass_context
def main(ctx: click.Context, color: str) -> None:
    """YAML behaviour-tree missions for a simulated Thymio II (no ROS, no Gazebo)."""
    if color == "always":
        ctx.color = True
    elif color == "never" or os.environ.get("NO_COLOR"):  # https://no-color.org: any non-empty value
        ctx.color = False
