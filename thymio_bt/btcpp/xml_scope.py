"""BehaviorTree.CPP 4's blackboard scopes, for XML missions: each ``<SubTree>`` instance has a
blackboard of its own in BT.CPP, thymio-bt runs on one (py_trees'), so the XML reader renames every
key a node names, as it reads the node, to the entry that key stands for in BT.CPP.

A :class:`Scope` is the blackboard of the main tree (keys as written) or of one subtree instance,
whose keys resolve as BT.CPP's ``Blackboard::getEntry`` and ``createEntryImpl`` do: a port the
``<SubTree>`` set to a literal is an entry of the instance holding that text; a port remapped to
``{key}`` is the parent's ``key`` (resolved in the parent, and so on up); with ``_autoremap="true"``
any other key not starting with ``_`` is the parent's key of the same name; ``@key`` is the main
tree's ``key``; any other key is the instance's own, named ``__N_ID__key`` (``N`` counts the
subtree instances in reading order, so each has its own entries, as in BT.CPP).

A literal port is read as its text where a node reads it; a node that writes it (a script's
``:=``, ``SetBlackboard``, ``UnsetBlackboard``, a leaf's key parameter) is an error.

Example::

    >>> ports = subtree_ports({"ID": "Leg", "goal": "{target}", "speed": "0.1"}, None, "Leg", ("m.xml", 7, 5))
    >>> leg = Scope().child(1, "Leg", ports)
    >>> leg.read("goal"), leg.read("turns"), leg.read("@turns"), leg.read("speed").text
    ('target', '__1_Leg__turns', 'turns', '0.1')
    >>> rename_script("turns := turns + speed; goal == 3", leg, ("m.xml", 9, 5))
    "__1_Leg__turns := __1_Leg__turns + '0.1'; target == 3"
    >>> leg.write("speed", ("m.xml", 9, 5))
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: m.xml:9:5: this node writes 'speed', which <SubTree ID="Leg"> sets to the literal ...
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache, lru_cache

from thymio_bt.btcpp.runtime.control import CONDITION_ATTRS
from thymio_bt.btcpp.runtime.script import _TOKEN, ScriptError, parse
from thymio_bt.errors import Problem, UserError

Where = tuple[str, int, int]

#: the script operators that write the name before them
_ASSIGN = (":=", "=", "+=", "-=", "*=", "/=")
#: attributes of a ``<SubTree>`` that are not ports (BT.CPP's ``IsReservedAttribute``)
_RESERVED = frozenset({"name", "ID", "_autoremap", *CONDITION_ATTRS})


@dataclass(frozen=True)
class Literal:
    """A subtree's port set to a text (``<SubTree ID="Leg" speed="0.1"/>``): where nodes read the
    port, they read this text."""

    text: str
    port: str
    subtree: str
    where: Where


@dataclass(frozen=True)
class Ports:
    """What one ``<SubTree>`` element sets: ports remapped to the parent's keys, literal ports, and
    whether the parent's other keys are visible (``_autoremap``)."""

    remap: Mapping[str, str] = field(default_factory=dict)
    literals: Mapping[str, Literal] = field(default_factory=dict)
    autoremap: bool = False


class Scope:
    """The blackboard of the main tree (no parent) or of one subtree instance (see the module)."""

    def __init__(self, parent: Scope | None = None, prefix: str = "", ports: Ports | None = None) -> None:
        self.parent, self.prefix, self.ports = parent, prefix, ports or Ports()

    def child(self, number: int, ident: str, ports: Ports) -> Scope:
        """The scope of the ``number``-th subtree instance read, of the ``<BehaviorTree ID=ident>``."""
        return Scope(self, f"__{number}_{_plain(ident)}__", ports)

    def read(self, key: str) -> str | Literal:
        """The entry ``key`` names here: a key of thymio-bt's blackboard, or a literal port."""
        if key.startswith("@") or self.parent is None:
            return key.lstrip("@")  # the root blackboard: '@key' is 'key' there
        if key in self.ports.literals:
            return self.ports.literals[key]
        if key in self.ports.remap:
            return self.parent.read(self.ports.remap[key])
        if self.ports.autoremap and not key.startswith("_"):
            return self.parent.read(key)
        return self.prefix + key

    def write(self, key: str, where: Where) -> str:
        """The entry a node at ``where`` writes as ``key``; a literal port cannot be written."""
        found = self.read(key)
        if isinstance(found, Literal):
            raise _literal_written(key, found, where)
        return found

    def local(self, key: str, where: Where) -> str:
        """The instance's own entry ``key`` (what ``UnsetBlackboard`` removes: BT.CPP's ``unset``
        looks in the instance's own storage only, so a remapped key is left alone)."""
        if self.parent is not None and key in self.ports.literals:
            raise _literal_written(key, self.ports.literals[key], where)
        return self.prefix + key


@cache
def _plain(ident: str) -> str:
    """``ident`` with only letters, digits and ``_`` (a key of the script language)."""
    return re.sub(r"[^A-Za-z0-9_]", "_", ident)


def _literal_written(key: str, literal: Literal, where: Where) -> UserError:
    """The error for a node at ``where`` that writes the literal port ``key``."""
    file, line, column = literal.where
    return UserError(
        Problem(
            f"this node writes '{key}', which <SubTree ID=\"{literal.subtree}\"> sets to the literal "
            f"'{literal.text}' ({file}:{line}:{column})",
            *where,
            hint=f'a literal port is read as its text: remap it to an entry instead ({literal.port}="{{key}}")',
        )
    )


def pointer(text: str) -> str | None:
    """The key of a blackboard pointer ``{key}`` (BT.CPP's ``isBlackboardPointer``), else None."""
    stripped = text.strip()
    if len(stripped) >= 3 and stripped[0] == "{" and stripped[-1] == "}" and stripped[1:-1].strip():
        return stripped[1:-1].strip()
    return None


def subtree_ports(
    attrs: Mapping[str, str], model: Mapping[str, tuple[str | None, Where]] | None, ident: str, where: Where
) -> Ports:
    """The ports a ``<SubTree>`` element (``attrs``, at ``where``) sets, with the defaults of its
    ``<TreeNodesModel>`` entry (``model``: port -> (default or None, where it is)), as BT.CPP's
    ``XMLParser`` reads them: ``{=}`` is ``{port}``; a model's port neither set nor defaulted is an
    error unless ``_autoremap``."""
    autoremap = False
    remapping: dict[str, tuple[str, Where]] = {}
    for name, value in attrs.items():
        if name == "_autoremap":
            autoremap = _flag(value, where)
        elif name[:1].isascii() and name[:1].isalpha() and name not in _RESERVED:
            remapping[name] = ("{" + name + "}" if value == "{=}" else value, where)
    for port, (default, at) in (model or {}).items():
        if port in remapping or autoremap:
            continue
        if not default:
            raise UserError(
                Problem(
                    f"<SubTree ID=\"{ident}\"> does not set its port '{port}', which has no default",
                    *where,
                    hint=f'set it ({port}="{{key}}" or a value), or give it a default in the <TreeNodesModel> '
                    f"(line {at[1]})",
                )
            )
        remapping[port] = (default, at)
    remap: dict[str, str] = {}
    literals: dict[str, Literal] = {}
    for name, (value, at) in remapping.items():
        key = pointer(value)
        if key is None:
            literals[name] = Literal(value, name, ident, at)
        else:
            remap[name] = key
    return Ports(remap, literals, autoremap)


def _flag(text: str, where: Where) -> bool:
    """``_autoremap``'s value, as BT.CPP's ``convertFromString<bool>`` reads it."""
    if text in ("1", "true", "TRUE", "True"):
        return True
    if text in ("0", "false", "FALSE", "False"):
        return False
    raise UserError(Problem(f'_autoremap="{text}" is not true or false', *where, hint='_autoremap="true"'))


def rename_script(text: str, scope: Scope, where: Where) -> str:
    """The script ``text`` of a node at ``where`` with each blackboard key renamed for ``scope`` (a
    literal port read as a quoted string). A script that does not parse is left as written: the
    node's check reports it, as the user wrote it."""
    names = _names(text)
    if not names:
        return text
    parts, last = [], 0
    for start, stop, name, writes in names:
        if writes:
            new = scope.write(name, where)
        else:
            found = scope.read(name)
            new = found if isinstance(found, str) else _quoted(found, where)
        parts += [text[last:start], new]
        last = stop
    return "".join(parts) + text[last:]


@lru_cache(maxsize=256)
def _names(text: str) -> tuple[tuple[int, int, str, bool], ...]:
    """Where the script ``text`` names blackboard entries: (start, end, name, whether it writes
    it); none for a script that does not parse. Read once per text, however many subtree
    instances copy it."""
    try:
        parse(text)
    except ScriptError:
        return ()
    tokens = []
    position, end = 0, len(text.rstrip())
    while position < end:
        match = _TOKEN.match(text, position, end)
        if match is None or match.end() == position:  # pragma: no cover - parse() accepted the text
            return ()
        kind = match.lastgroup or ""
        tokens.append((kind, match.start(kind), match.end(kind), match.group(kind)))
        position = match.end()
    names = []
    for index, (kind, start, stop, value) in enumerate(tokens):
        if kind == "name" and value not in ("true", "false"):
            following = tokens[index + 1] if index + 1 < len(tokens) else None
            writes = following is not None and following[0] == "op" and following[3] in _ASSIGN
            names.append((start, stop, value, writes))
    return tuple(names)


def _quoted(literal: Literal, where: Where) -> str:
    """A literal port as a string of the script language."""
    for quote in ("'", '"'):
        if quote not in literal.text:
            return quote + literal.text + quote
    raise UserError(
        Problem(
            f"a script reads '{literal.port}', set to a literal with both kinds of quotes",
            *where,
            hint="the script language has no escapes: remap the port to an entry instead",
        )
    )
