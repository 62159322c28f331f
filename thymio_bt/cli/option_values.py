"""What the options several commands share ask for: the backend of ``--backend`` and
``--backend-opt`` (``run``, ``compare``, ``calibrate``) and the coverage of ``--coverage`` and
``--coverage-tree`` (``run``, ``sweep``). A module of its own, so that a command needing one of them
does not import another command's module.

Example::

    >>> from thymio_bt.mission import load_mission
    >>> device = backend_for(load_mission("square"), seed=None, name=None, opts=())  # the mission's: sim
    >>> type(device).__name__, device.time()
    ('Simulation', 0.0)
    >>> device.close()
    >>> backend_for(load_mission("square"), seed=None, name="sim", opts=("device",))
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: --backend-opt expects NAME=VALUE, got 'device' (hint: --backend-opt device=/dev/ttyACM0)
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from thymio_bt.cli.app import parse_pairs
from thymio_bt.errors import UserError
from thymio_bt.outputs import Output

if TYPE_CHECKING:
    from thymio_bt.plan.model import Mission
    from thymio_bt.robot.interface import Backend


def backend_for(spec: Mission, seed: int | None, name: str | None, opts: tuple[str, ...]) -> Backend:
    """The backend the run asked for (``--backend`` over the mission's), connected and ready.

    ``opts`` are the ``--backend-opt KEY=VALUE`` options; they add to the mission's ``backend:``
    options when ``name`` is the mission's backend, and replace them otherwise.
    """
    from thymio_bt.backends import backend_kind

    options = dict(spec.backend_options) if name is None or name == spec.backend else {}
    options.update(parse_pairs(opts, "--backend-opt", "device=/dev/ttyACM0"))
    kind = backend_kind(spec.backend if name is None else name)  # --backend '' is no backend, not the default
    return kind.create(spec, spec.seed if seed is None else seed, options)


class CoverageRequest:
    """What ``--coverage`` and ``--coverage-tree FILE`` ask of ``run`` and ``sweep``: the coverage
    printed as a tree after the summary (:attr:`text`) and drawn to the file when one is named."""

    def __init__(self, out: Output | None, fmt: str) -> None:
        self.out, self.fmt = out, fmt
        #: the coverage JSON and its tree as text, once :meth:`done`
        self.data: dict[str, Any] = {}
        self.text: str | None = None

    @classmethod
    def checked(cls, tree: Path | None) -> CoverageRequest:
        """The request, its file (``tree``) checked before anything runs: writable, a known suffix."""
        if tree is None:
            return cls(None, "")
        fmt = tree.suffix.lower().lstrip(".")
        if fmt not in ("dot", "svg", "png"):
            raise UserError(
                f"--coverage-tree {tree}: cannot tell the format from '{tree.suffix or 'no extension'}' "
                "(hint: end the name with .dot, .svg or .png)"
            )
        return cls(Output(tree, "--coverage-tree"), fmt)

    def done(self, conditions: set[str], data: dict[str, Any], registry: Any = None) -> None:
        """Keep the coverage JSON ``data`` and its text (``conditions``: the names of the nodes to show
        as true and false; ``registry``: the mission's nodes); draw it to the file."""
        from thymio_bt.viz.graph import coverage_dot, write_graph
        from thymio_bt.viz.terminal import coverage_text

        self.data, self.text = data, coverage_text(data, conditions, registry)
        if self.out is not None:
            write_graph(coverage_dot(data, conditions, registry), self.out, self.fmt, "--coverage-tree coverage.dot")
