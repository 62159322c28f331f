"""``thymio-bt serve ros2``: our simulation standing in for the course's Gazebo world over ROS 2.

Example::

    >>> from thymio_bt.maze import load_maze, resolve_maze
    >>> world = load_maze(resolve_maze("two_parts_maze"))
    >>> start_pose(world, "0.5,0.3,0").as_tuple()
    (0.5, 0.3, 0.0)
    >>> start_pose(world, "nowhere")
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: --start nowhere: maze 'two_parts_maze' has no such spawn (hint: ...)
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING, NoReturn

import click

from thymio_bt.cli.app import POSITIVE, fail, main
from thymio_bt.errors import UserError

if TYPE_CHECKING:
    from thymio_bt.geometry import Pose
    from thymio_bt.maze import Maze
    from thymio_bt.run.interrupts import Interrupted


@main.group()
def serve() -> None:
    """Serve our simulation to other tools (ROS 2 nodes)."""


@serve.command("ros2")
@click.option(
    "--maze",
    "maze_ref",
    default="two_parts_maze",
    show_default=True,
    help="The maze: a file, or the name of a shipped maze.",
)
@click.option(
    "--start",
    default=None,
    metavar="X,Y,YAW",
    help="The robot's pose at start (base_link), or a spawn of the maze; default: its first spawn.",
)
@click.option(
    "--speedup", type=POSITIVE, default=1.0, show_default=True, help="Run at real time x this (the course's Gazebo: 1)."
)
@click.option("--robot", default="course", show_default=True, help="The robot model simulated.")
@click.option("--quiet", "-q", is_flag=True, help="Print nothing but errors.")
def serve_ros2(maze_ref: str, start: str | None, speedup: float, robot: str, quiet: bool) -> None:
    """Stand in for the course's Gazebo world: its topics, services, TF and /clock over ROS 2.

    A node written for the course (cmd_vel, odom, the /thymio_*_sensor scans, /spawn_entity,
    /delete_entity) runs against it unchanged; so does 'thymio-bt run MISSION --backend ros2'.
    Ctrl-C or SIGTERM stops it (exit 0); a step stuck 2 s after the signal is broken into (exit 130/143).
    """
    from thymio_bt.geometry import Pose
    from thymio_bt.maze.files import load_maze, resolve_maze
    from thymio_bt.robot.model import robot_model
    from thymio_bt.robot.placement import placement_problem
    from thymio_bt.run.interrupts import Interrupted, Interrupts

    try:
        interrupts = Interrupts()  # first: a bad THYMIO_BT_INTERRUPT_GRACE is said before ROS starts
        model = robot_model(robot)
        world = load_maze(resolve_maze(maze_ref))
        pose = start_pose(world, start)
        problem = placement_problem(world, model, pose)
        if problem:
            raise UserError(
                f"--start {start or ''}: impossible start pose: {problem} (hint: pick a free pose "
                f"inside the maze{', e.g. one of its spawns: ' + ', '.join(world.spawns) if world.spawns else ''})"
            )
        from thymio_bt.backends.ros2.serve import GazeboStandIn

        stand_in = GazeboStandIn(world, Pose(*pose.as_tuple()), model, speedup)
    except UserError as exc:
        fail(exc)
    domain = os.environ.get("ROS_DOMAIN_ID", "0")
    if not quiet:
        click.echo(
            f"serving {world.name} over ROS 2 (domain {domain}), thymio at x={pose.x:g} y={pose.y:g} "
            f"yaw={pose.yaw:g}, {speedup:g}x real time; Ctrl-C stops",
            err=True,
        )

    def progress(sim_time: float, achieved: float) -> None:
        if not quiet and sys.stderr.isatty():
            click.echo(f"\r  {sim_time:8.0f} s simulated, {achieved:5.2f}x real time", err=True, nl=False)

    broken: Interrupted | None = None
    try:
        with interrupts:
            stand_in.run(stop=lambda: interrupts.signal is not None, on_second=progress)
    except Interrupted as exc:  # a step that never ended, broken into: stop anyway, say so
        broken = exc
    finally:
        stand_in.close()
    if broken is not None:
        _broken_into(broken)
    if not quiet:
        click.echo("\nstopped", err=True)


def _broken_into(exc: Interrupted) -> NoReturn:
    """A step of the stand-in never ended after the signal and was broken into: exit with the signal's
    code (130, 143), even if a thread stuck with it would keep the process alive."""
    from thymio_bt.run.leftovers import end_despite_threads

    click.echo(f"\nstopped: a step of the simulation never ended; {exc.how} ({exc.name})", err=True)
    end_despite_threads(exc.exit_code)
    sys.exit(exc.exit_code)


def start_pose(world: Maze, start: str | None) -> Pose:
    """The start pose of ``serve``: ``X,Y,YAW``, a spawn of the maze, or the maze's first spawn."""
    from thymio_bt.geometry import Pose
    from thymio_bt.inputs.units import UnitError, parse_pose

    if start is None or "," not in start:
        names = list(world.spawns)
        if start is None and not names:
            raise UserError(f"maze '{world.name}' names no spawn (hint: pass --start X,Y,YAW)")
        if start is not None and start not in world.spawns:
            from thymio_bt.errors import did_you_mean

            raise UserError(
                f"--start {start}: maze '{world.name}' has no such spawn (hint: "
                f"{did_you_mean(start, names) if names else 'give X,Y,YAW'})"
            )
        return world.spawn(start or names[0])
    try:
        return Pose(*parse_pose(start))
    except UnitError as exc:
        raise UserError(f"--start {start}: {exc} (hint: {exc.hint or 'e.g. --start 0.5,0.3,pi/2'})") from None
