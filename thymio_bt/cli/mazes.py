"""``thymio-bt maze import`` and ``thymio-bt maze export``: mazes from and to other tools' files.

``import`` reads a Gazebo classic world of box walls or a micromouse contest maze (``.txt``) into a
maze file; ``export --playground`` writes a maze as an Aseba Playground world with one Thymio.

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> from thymio_bt.maze import resolve_maze
    >>> result = CliRunner().invoke(main, ["maze", "export", str(resolve_maze("two_parts_maze")), "--playground"])
    >>> result.exit_code, result.output.splitlines()[:2]
    (0, ['<!DOCTYPE aseba-playground>', '<aseba-playground>'])
"""

from __future__ import annotations

from pathlib import Path

import click

from thymio_bt.cli.app import POSITIVE, fail, main, path_option
from thymio_bt.errors import UserError
from thymio_bt.outputs import STDOUT, Output


@main.group()
def maze() -> None:
    """Maze tools."""


@maze.command("import")
@click.argument("world", type=click.Path(path_type=Path))
@path_option("--output", "-o", default=STDOUT, show_default=True, help="Maze YAML to write (- = standard output).")
@click.option("--model", default=None, help="Import only this model of the world.")
@click.option("--cell", type=POSITIVE, default=0.18, show_default=True, help="Micromouse: cell size (m).")
@click.option("--wall", type=POSITIVE, default=0.012, show_default=True, help="Micromouse: wall thickness (m).")
@click.option("--post", type=POSITIVE, default=0.012, show_default=True, help="Micromouse: post size (m).")
def maze_import(world: Path, output: Path, model: str | None, cell: float, wall: float, post: float) -> None:
    """Convert a Gazebo classic WORLD file of box walls, or a micromouse contest maze (.txt), into a maze file."""
    import yaml

    try:
        out = Output(output, "--output")
        if world.suffix.lower() == ".txt":
            from thymio_bt.maze.micromouse import read_micromouse

            result = read_micromouse(world, cell, wall, post)
        else:
            from thymio_bt.maze.gazebo import import_world

            result = import_world(world, model)
        text = (
            f"# Made by: thymio-bt maze import {world}"
            + ("" if out.is_stdout else f" -o {output}")
            + "\n"
            + yaml.safe_dump(result.to_yaml_dict(), sort_keys=False)
        )
        _check_size(text, world)
        out.write_text(text)
    except UserError as exc:
        fail(exc)
    if not out.is_stdout:
        click.echo(f"wrote {output}: {len(result.walls)} walls", err=True)


def _check_size(text: str, world: Path) -> None:
    """Refuse a maze file that the maze loader would refuse for its size (``LIMITS["maze"]``), before
    anything is written (a 0.5 MB maze already takes about 2 s to load and check)."""
    from thymio_bt.errors import Problem
    from thymio_bt.inputs.reading import LIMITS, MB

    size, cap = len(text.encode()), LIMITS["maze"]
    if size > cap:
        raise UserError(
            Problem(
                f"the maze would be {size / MB:.1f} MB, over the {cap / MB:g} MB a maze file may have",
                str(world),
                hint="import one model of the world (--model NAME), or fewer walls",
            )
        )


@maze.command("export")
@click.argument("maze_file", type=click.Path(path_type=Path))
@click.option(
    "--playground",
    "playground",
    is_flag=True,
    required=True,
    help="As an Aseba Playground world (the only export format so far).",
)
@click.option("--spawn", default=None, help="The robot's place: a spawn of the maze (default: its first).")
@click.option("--robot", default="enki", show_default=True, help="The robot model (its wheel axle is placed).")
@click.option(
    "--port", type=click.IntRange(1, 65535), default=33333, show_default=True, help="The robot's Aseba TCP port."
)
@path_option("--output", "-o", default=STDOUT, show_default=True, help="World file to write (- = standard output).")
def maze_export(maze_file: Path, playground: bool, spawn: str | None, robot: str, port: int, output: Path) -> None:
    """Write MAZE_FILE (.yaml, grid or .txt) as an Aseba Playground world with one Thymio."""
    from thymio_bt.backends.playground.world import playground_world
    from thymio_bt.geometry import Pose
    from thymio_bt.maze.files import load_maze
    from thymio_bt.robot.model import robot_model

    try:
        out = Output(output, "--output")
        result = load_maze(maze_file)
        names = list(result.spawns)
        if spawn is None and not names:
            raise UserError(f"{maze_file} names no spawn (hint: pass --spawn NAME, or add spawns: to the maze)")
        pose = result.spawn(spawn or names[0])
        world = playground_world(result, Pose(*robot_model(robot).axle_of(pose)), port)
        out.write_text(world.text)
    except UserError as exc:
        fail(exc)
    if not out.is_stdout:
        click.echo(f"wrote {output}: {len(result.walls)} walls, the robot on port {port}", err=True)
