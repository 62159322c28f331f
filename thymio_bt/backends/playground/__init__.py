"""The Aseba Playground (the Thymio makers' simulator, on Enki physics) as a thymio-bt backend.

``run --backend playground`` starts a headless Playground with a world made from the mission's maze
(:mod:`.world`), on a private D-Bus session bus and a free port (:mod:`.process`), drives its Thymio
through the same Aseba code as a real robot (:mod:`thymio_bt.backends.real.aseba`), and uses the
Playground's D-Bus interface for the ground truth, spawning (teleport) and deleting (parking the
robot outside the maze) (:mod:`.enki`, :mod:`.backend`). It runs in real time.
"""
