"""The pictures ``run`` and ``replay`` draw of a run: ``--plot``, ``--plot-signals`` and ``--gif``.

They are checked before the run (a format that cannot be written, a missing folder) so that a long
run does not end in an error, and drawn from its recording afterwards.

Example::

    >>> from pathlib import Path
    >>> Pictures(plot=Path("path.png"), plot_signals=None, gif=None).wanted
    True
    >>> Pictures(plot=None, plot_signals=None, gif=Path("run.avi")).check()
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: --gif run.avi: cannot write '.avi' (hint: use .gif, .mp4)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

import click

from thymio_bt.errors import UserError
from thymio_bt.outputs import check_writable

if TYPE_CHECKING:
    from thymio_bt.logs.recording import Recording

#: what --plot/--plot-signals (matplotlib) and --gif (Pillow, or ffmpeg for .mp4) can write
PICTURE_SUFFIXES = {
    "--plot": (".png", ".svg", ".pdf", ".jpg"),
    "--plot-signals": (".png", ".svg", ".pdf", ".jpg"),
    "--gif": (".gif", ".mp4"),
}


class Pictures(NamedTuple):
    """The picture files a command was asked for (``None``: not asked).

    A named tuple, not a dataclass: making a dataclass costs the command line's start-up a few ms.
    """

    plot: Path | None
    plot_signals: Path | None
    gif: Path | None

    @property
    def wanted(self) -> bool:
        """Whether any picture was asked for (then the run must be recorded)."""
        return bool(self.plot or self.plot_signals or self.gif)

    def check(self) -> None:
        """Refuse, before the run, a picture whose format cannot be written or whose folder is missing."""
        for option, path in (("--plot", self.plot), ("--plot-signals", self.plot_signals), ("--gif", self.gif)):
            if path is None:
                continue
            suffixes = PICTURE_SUFFIXES[option]
            if path.suffix.lower() not in suffixes:
                raise UserError(
                    f"{option} {path}: cannot write '{path.suffix or 'no extension'}' (hint: use {', '.join(suffixes)})"
                )
            check_writable(path, option)
            if option == "--gif" and path.suffix.lower() == ".mp4":
                from thymio_bt.viz.animation import ffmpeg_program

                ffmpeg_program(path)  # a run must not end in "ffmpeg is not installed"

    def draw(self, recording: Recording, speedup: float, quiet: bool) -> None:
        """Draw the pictures asked for from ``recording`` (``speedup``: of the animation), saying what was written."""
        if not self.wanted:
            return
        from thymio_bt.viz import animation, plots

        for path, draw in ((self.plot, plots.plot_run), (self.plot_signals, plots.plot_signals)):
            if path is not None:
                draw(recording, path)
                if not quiet:
                    click.echo(f"wrote {path}", err=True)
        if self.gif is not None:
            animation.animate(recording, self.gif, speedup=speedup)
            if not quiet:
                click.echo(f"wrote {self.gif}", err=True)
