"""``thymio-bt calibrate``: measure a robot (simulated or real) into a profile for ``--robot FILE.yaml``.

The measurement runs in a corridor maze written to a temporary folder with a one-node mission, on
the backend asked for; :mod:`thymio_bt.robot.calibrate` does the measuring.

Example::

    >>> from click.testing import CliRunner
    >>> from thymio_bt.cli import main
    >>> result = CliRunner().invoke(main, ["calibrate", "-o", "my_thymio.txt"])
    >>> result.exit_code
    2
    >>> print(result.output, end="")
    error: --output my_thymio.txt: a profile is a .yaml file (hint: -o my_thymio.yaml)
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import click

from thymio_bt.cli.app import backend_options, fail, main
from thymio_bt.cli.option_values import backend_for
from thymio_bt.errors import UserError
from thymio_bt.outputs import Output
from thymio_bt.run.interrupts import Interrupts

if TYPE_CHECKING:
    from thymio_bt.plan.model import Mission
    from thymio_bt.robot.interface import Backend


@main.command("calibrate")
@backend_options("The robot to measure: playground, aseba (a real Thymio), sim, ... (see 'thymio-bt backends').", "sim")
@click.option(
    "--robot", default="enki", show_default=True, help="The built-in model to start from (course, enki, real)."
)
@click.option(
    "--output", "-o", type=click.Path(path_type=Path), required=True, help="The profile file to write (.yaml)."
)
@click.option("--name", default=None, help="The profile's name (default: the file's name).")
def calibrate_command(backend: str, backend_opts: tuple[str, ...], robot: str, output: Path, name: str | None) -> None:
    """Measure a robot's speed scale, wheel base and proximity response into a profile for --robot.

    The robot faces a wall along a corridor (a simulator builds it; a real robot is placed at the
    printed pose): 2 s straight, a slow approach to 8 mm, a spin. About 25 s in real time.
    """
    from thymio_bt.robot.calibrate import Stopped, calibrate
    from thymio_bt.robot.interface import RobotLost
    from thymio_bt.robot.profile import profile_text

    try:
        out = Output(output, "--output")
        _check_request(output, robot)
        spec, device = _corridor(robot, backend, backend_opts)
        try:
            device.request_spawn(device.robot_name, spec.start)
            device.advance(0.0)
            with Interrupts() as interrupts:  # Ctrl-C and SIGTERM: asked after every tick
                result = calibrate(
                    device,
                    device.model,
                    spec.maze,
                    say=lambda text: click.echo(text, err=True),
                    stopped=lambda: interrupts.signal is not None,
                )
        except Stopped as exc:
            _interrupted(interrupts, exc, output)
        except (ValueError, RobotLost) as exc:
            raise UserError(f"calibrate: {exc}") from None
        finally:
            device.close()  # the motors stopped, the Playground (or the link) closed
        out.write_text(profile_text(result.profile(name or output.stem)))
    except UserError as exc:
        fail(exc)
    for line in result.summary():
        click.echo(line)
    click.echo(f"wrote {output}: use it with --robot {output}", err=True)


def _interrupted(interrupts: Interrupts, stopped: Exception, output: Path) -> NoReturn:
    """A Ctrl-C or SIGTERM stopped the measuring: say so, write nothing, exit with the signal's code
    (130, 143) as ``run`` does, even if a leftover thread would keep the process alive."""
    from thymio_bt.run.leftovers import end_despite_threads

    click.echo(f"calibrate: interrupted by {interrupts.name}, {stopped}: {output} not written", err=True)
    end_despite_threads(interrupts.exit_code)
    sys.exit(interrupts.exit_code)


def _check_request(output: Path, robot: str) -> None:
    """Refuse a profile file that is not YAML, or a robot that is not a built-in model."""
    from thymio_bt.robot.model import ROBOTS

    if output.suffix.lower() not in (".yaml", ".yml"):
        raise UserError(f"--output {output}: a profile is a .yaml file (hint: -o my_thymio.yaml)")
    if robot not in ROBOTS:
        from thymio_bt.errors import did_you_mean

        raise UserError(
            f"--robot {robot}: calibrate starts from a built-in model (hint: {did_you_mean(robot, ROBOTS)})"
        )


def _corridor(robot: str, backend: str, backend_opts: tuple[str, ...]) -> tuple[Mission, Backend]:
    """The calibration mission (the corridor, ``robot`` at its start) and the backend to run it on, connected."""
    import tempfile

    import yaml

    from thymio_bt.mission import load_mission
    from thymio_bt.robot.calibrate import arena
    from thymio_bt.robot.model import robot_model

    # a robot whose simulated sensors give metres (the course's rays) is measured through its
    # calibration, as a real robot's readings: calibrate measures readings
    sensors = "sensor_model: raw\n" if robot_model(robot).sensor_model == "rays" else ""
    with tempfile.TemporaryDirectory() as tmp:
        maze_file = Path(tmp) / "corridor.yaml"
        maze_file.write_text(yaml.safe_dump(arena().to_yaml_dict(), sort_keys=False))
        mission_file = Path(tmp) / "calibrate.yaml"
        mission_file.write_text(
            f"name: calibrate\nmaze: {maze_file}\nstart: start\nrobot: {robot}\n{sensors}time_limit: 120\n"
            "tree:\n  Stop: {}\n"
        )
        spec = load_mission(mission_file)
        device = backend_for(spec, 0, backend, backend_opts)
    return spec, device
