"""What the operating system forbids a submission's process: called in that process, after it has
imported what it needs and before it reads the submission.

- **files** (Landlock ABI 1+): it reads the Python installation and its own copy of the submission,
  writes only its private temporary folder;
- **network** (Landlock ABI 4+): no TCP connection, no TCP port bound;
- **signals** (Landlock ABI 6+): it cannot signal processes outside its own Landlock domain, nor
  reach their abstract UNIX sockets (ptrace of other processes is denied by Landlock from ABI 1);
- **processes**: at most :data:`NPROC_MARGIN` more processes: ``RLIMIT_NPROC`` over the user's
  processes now, or, as root (whom ``RLIMIT_NPROC`` does not bind), a ``pids`` cgroup of its own
  (:mod:`.reaping`); every one it starts is killed when its run ends; no capability,
  ``no_new_privs``; memory (``RLIMIT_AS``), CPU and file size limits.

Landlock is three system calls (``landlock_create_ruleset``, ``landlock_add_rule``,
``landlock_restrict_self``), here through ctypes; a kernel without it, or another OS, leaves what it
covers missing, and :func:`plan` says why before anything runs (``grade --require-confinement``).

Example (what this machine grants; the set depends on its kernel)::

    >>> held = plan()
    >>> sorted(held.held + list(held.missing)) == sorted(AREAS)
    True
"""

from __future__ import annotations

import ctypes
import errno
import os
import resource
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from thymio_bt.errors import ThymioBtError
from thymio_bt.grade.reaping import pids_cgroups

#: what a submission's process may be confined in, in the order the summary names them
AREAS = ("files", "network", "signals", "processes")
#: the Landlock ABI each area needs
_NEEDS = {"files": 1, "network": 4, "signals": 6}
_KERNEL = {1: "5.13", 4: "6.7", 6: "6.12"}

# Landlock's system calls (the same numbers on every architecture since 5.13) and flags
_CREATE, _ADD, _RESTRICT = 444, 445, 446
_CREATE_RULESET_VERSION = 1
_RULE_PATH_BENEATH, _RULE_NET_PORT = 1, 2
_FS_ABI1 = (1 << 13) - 1  # execute, write, read file/dir, remove, make char/dir/reg/sock/fifo/block/sym
_FS_REFER, _FS_TRUNCATE, _FS_IOCTL_DEV = 1 << 13, 1 << 14, 1 << 15
_EXECUTE, _WRITE_FILE, _READ_FILE, _READ_DIR = 1, 1 << 1, 1 << 2, 1 << 3
_NET_BIND_TCP, _NET_CONNECT_TCP = 1, 2
_SCOPE_ABSTRACT_UNIX, _SCOPE_SIGNAL = 1, 2
_PR_SET_NO_NEW_PRIVS, _PR_CAPBSET_DROP, _PR_CAP_AMBIENT, _PR_CAP_AMBIENT_CLEAR_ALL = 38, 24, 47, 4
#: how many processes (and threads) a submission may start
NPROC_MARGIN = 32


class _RulesetAttr(ctypes.Structure):
    _fields_ = (("fs", ctypes.c_uint64), ("net", ctypes.c_uint64), ("scoped", ctypes.c_uint64))


class _PathBeneath(ctypes.Structure):
    _pack_ = 1
    _fields_ = (("allowed", ctypes.c_uint64), ("parent_fd", ctypes.c_int32))


class ConfinementError(ThymioBtError):
    """A step of the confinement failed where :func:`plan` said it would hold."""


@dataclass
class Confinement:
    """Which areas hold, and for each missing one why (an old kernel, another OS)."""

    held: list[str] = field(default_factory=list)
    missing: dict[str, str] = field(default_factory=dict)

    def summary(self) -> str:
        """The grade summary's line.

        >>> Confinement(["files", "processes"], {"signals": "Landlock ABI 4 (kernel < 6.12)"}).summary()
        'confined: files, processes; not confined: signals (Landlock ABI 4 (kernel < 6.12))'
        """
        text = f"confined: {', '.join(self.held) or 'nothing'}"
        if self.missing:
            text += "; not confined: " + ", ".join(f"{k} ({why})" for k, why in self.missing.items())
        return text


def landlock_abi() -> int:
    """The kernel's Landlock ABI version; 0 when it has none (or it is disabled, or not Linux)."""
    if not sys.platform.startswith("linux"):
        return 0
    libc = ctypes.CDLL(None, use_errno=True)
    version = libc.syscall(_CREATE, None, ctypes.c_size_t(0), ctypes.c_uint32(_CREATE_RULESET_VERSION))
    return max(0, int(version))


def plan() -> Confinement:
    """What a submission's process will be confined in on this machine (as this user)."""
    if not sys.platform.startswith("linux"):
        why = f"not Linux ({sys.platform}): no Landlock"
        return Confinement([], {area: why for area in AREAS})
    abi = landlock_abi()
    result = Confinement()
    for area in AREAS:
        need = _NEEDS.get(area, 0)
        if area == "processes" and os.geteuid() == 0 and not pids_cgroups():
            result.missing[area] = "forks unbounded: root, whom RLIMIT_NPROC does not bind, and no pids cgroup"
        elif abi >= need:
            result.held.append(area)
        elif abi == 0:
            result.missing[area] = "no Landlock in this kernel (Linux 5.13+ with landlock in lsm=)"
        else:
            result.missing[area] = f"Landlock ABI {abi} < {need} (kernel older than {_KERNEL[need]})"
    return result


def confine(readable: Sequence[Path], writable: Path, memory: int, cpu: int) -> Confinement:
    """Confine this process for good (see the module's list): ``readable`` folders and files,
    ``writable`` the only folder it writes; ``memory`` bytes of address space, ``cpu`` seconds.
    What held, as :func:`plan` said."""
    held = plan()
    if not sys.platform.startswith("linux"):
        return held
    _limits(memory, cpu)
    _drop_capabilities()
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(_PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        raise ConfinementError(f"no_new_privs: {os.strerror(ctypes.get_errno())}")
    abi = landlock_abi()
    if abi >= 1:
        _landlock(libc, abi, readable, writable)
    return held


def _limits(memory: int, cpu: int) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 5))
    resource.setrlimit(resource.RLIMIT_FSIZE, (64 << 20, 64 << 20))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    if os.getuid() != 0:  # every process of the user counts (root is not bound: a pids cgroup is)
        nproc = _tasks_of(os.getuid()) + NPROC_MARGIN
        resource.setrlimit(resource.RLIMIT_NPROC, (nproc, nproc))


def _tasks_of(uid: int) -> int:
    """How many tasks (processes and threads: what RLIMIT_NPROC counts) user ``uid`` runs now."""
    count = 0
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            try:
                if os.stat(entry.path).st_uid == uid:
                    count += len(os.listdir(f"{entry.path}/task"))
            except OSError:
                continue
    return count


def _drop_capabilities() -> None:
    """No capability now or after an exec (the bounding set emptied first, while it may be)."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(_PR_CAP_AMBIENT, _PR_CAP_AMBIENT_CLEAR_ALL, 0, 0, 0)
    for cap in range(64):
        if libc.prctl(_PR_CAPBSET_DROP, cap, 0, 0, 0) != 0 and ctypes.get_errno() == errno.EINVAL:
            break  # past the last capability this kernel knows (EPERM: not ours to drop, nothing held)
    header = (ctypes.c_uint32 * 2)(0x20080522, 0)  # _LINUX_CAPABILITY_VERSION_3, this process
    data = (ctypes.c_uint32 * 6)()  # effective, permitted, inheritable (two words each): all empty
    if libc.capset(header, data) != 0:
        raise ConfinementError(f"capset: {os.strerror(ctypes.get_errno())}")


def _landlock(libc: ctypes.CDLL, abi: int, readable: Sequence[Path], writable: Path) -> None:
    fs = _FS_ABI1 | (_FS_REFER if abi >= 2 else 0) | (_FS_TRUNCATE if abi >= 3 else 0)
    fs |= _FS_IOCTL_DEV if abi >= 5 else 0
    attr = _RulesetAttr(
        fs,
        (_NET_BIND_TCP | _NET_CONNECT_TCP) if abi >= 4 else 0,
        (_SCOPE_ABSTRACT_UNIX | _SCOPE_SIGNAL) if abi >= 6 else 0,
    )
    size = ctypes.sizeof(_RulesetAttr) if abi >= 6 else (16 if abi >= 4 else 8)
    ruleset = libc.syscall(_CREATE, ctypes.byref(attr), ctypes.c_size_t(size), ctypes.c_uint32(0))
    if ruleset < 0:
        raise ConfinementError(f"landlock_create_ruleset: {os.strerror(ctypes.get_errno())}")
    try:
        read = _READ_FILE | _READ_DIR | _EXECUTE
        for path in readable:
            _allow(libc, ruleset, path, read)
        _allow(libc, ruleset, writable, fs & ~_EXECUTE)
        if libc.syscall(_RESTRICT, ruleset, ctypes.c_uint32(0)) != 0:
            raise ConfinementError(f"landlock_restrict_self: {os.strerror(ctypes.get_errno())}")
    finally:
        os.close(ruleset)


def _allow(libc: ctypes.CDLL, ruleset: int, path: Path, access: int) -> None:
    """Allow ``access`` beneath ``path`` (a file gets only the rights a file can have)."""
    try:
        fd = os.open(path, os.O_PATH | os.O_CLOEXEC)
    except OSError:
        return  # a folder this Python does not have: nothing to allow
    try:
        if not os.path.isdir(path):
            access &= _EXECUTE | _WRITE_FILE | _READ_FILE | _FS_TRUNCATE | _FS_IOCTL_DEV
        rule = _PathBeneath(access, fd)
        if libc.syscall(_ADD, ruleset, _RULE_PATH_BENEATH, ctypes.byref(rule), ctypes.c_uint32(0)) != 0:
            raise ConfinementError(f"landlock_add_rule {path}: {os.strerror(ctypes.get_errno())}")
    finally:
        os.close(fd)


def python_paths() -> list[Path]:
    """What the Python installation is: its prefixes, its import path and the system's libraries
    (the folders a confined process reads)."""
    import thymio_bt

    found = {Path(p) for p in (sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix)}
    found |= {Path(p) for p in sys.path if p and os.path.isdir(p)}
    found.add(Path(thymio_bt.__file__).parent)
    found |= {Path(p) for p in ("/usr/lib", "/usr/lib64", "/lib", "/lib64", "/usr/local/lib")}
    return sorted(found)
