"""Safe YAML loading that remembers where every key and item came from.

``load_yaml`` returns plain dicts and lists (subclasses :class:`MarkedDict` and :class:`MarkedList`)
whose ``.marks`` give the (line, column) of each key or item, so later validation can point at the
exact place of a problem. It never constructs Python objects (only standard tags), rejects
duplicate keys, and limits aliases so that "billion laughs" files cannot blow up time or memory.

Example::

    >>> from thymio_bt.data import MISSIONS
    >>> data = load_yaml(MISSIONS / "maze_part1_2.yaml")
    >>> data["start"], data.marks["start"], data.value_marks["start"]     # start: part1, on line 11
    ('part1', (11, 1), (11, 8))
    >>> data["tree"]["sequence"]["children"].marks[:2]                   # where the first two items are
    [(32, 9), (33, 9)]
    >>> loads_yaml("{a: 1, a: 2}", "m.yaml")
    Traceback (most recent call last):
    ...
    thymio_bt.errors.UserError: m.yaml:1:8: duplicate key 'a' (hint: 'a' is already given at line 1; ...)
"""

from __future__ import annotations

import copy
import functools
import re
import sys
from collections import OrderedDict
from pathlib import Path
from typing import Any

import yaml
from yaml.composer import Composer
from yaml.constructor import SafeConstructor
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode
from yaml.resolver import Resolver

from thymio_bt.errors import Problem, UserError
from thymio_bt.inputs.reading import read_text

#: Most alias uses accepted in one file; generous for hand-written missions.
MAX_ALIASES = 200
#: Most nodes that aliases may add when the document is expanded (a "billion laughs" file nests
#: aliases of aliases: few aliases, exponentially many nodes once expanded).
MAX_ALIAS_EXPANSION = 10_000
#: Deepest nesting of mappings and lists (far beyond any mission; keeps recursion bounded).
MAX_NESTING = 200

_STANDARD_TAG = "tag:yaml.org,2002:"

Mark = tuple[int, int]


#: the largest integer a file may hold: the largest a float can (about 1.8e308)
MAX_INT = int(sys.float_info.max)


class MarkedDict(dict):
    """A dict that knows the (line, column) of its own start and of each of its keys."""

    mark: Mark = (0, 0)
    #: the BT.CPP ``<SubTree ID=...>`` a node read from XML stands for (the XML reader sets it), else None
    subtree_use: str | None = None

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.marks: dict[Any, Mark] = {}
        self.value_marks: dict[Any, Mark] = {}


class MarkedList(list):
    """A list that knows the (line, column) of its own start and of each item."""

    mark: Mark = (0, 0)

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.marks: list[Mark] = []


def _mark(node: Node) -> Mark:
    """A node's (line, column), 1-based."""
    return node.start_mark.line + 1, node.start_mark.column + 1


def mark_of(data: Any, default: Mark = (0, 0)) -> Mark:
    """Where ``data`` starts in its file: a marked mapping's or list's (line, column), else ``default``
    (a plain value, or data built in code).

    >>> mark_of(loads_yaml("[1, [2]]")[1]), mark_of(3, (1, 1))
    ((1, 5), (1, 1))
    """
    return data.mark if isinstance(data, (MarkedDict, MarkedList)) else default


class _Loader(yaml.SafeLoader):
    """SafeLoader that records marks, rejects duplicate keys and counts aliases."""

    def __init__(self, stream: str, filename: str) -> None:
        super().__init__(stream)
        self._start(filename)

    def _start(self, filename: str) -> None:
        """The loader's own state, once its parser is set up."""
        self.filename = filename
        self.alias_count = 0
        self.problems: list[Problem] = []
        self._open_anchors: list[str] = []  # anchors of the nodes being composed, outermost first

    def _event_problem(self, message: str, hint: str) -> UserError:
        """A :class:`UserError` at the place of the next event (the node being composed)."""
        event = self.peek_event()
        return UserError(
            Problem(message, self.filename, event.start_mark.line + 1, event.start_mark.column + 1, hint=hint)
        )

    def compose_node(self, parent: Node | None, index: Any) -> Node | None:
        """Compose one node, counting aliases and refusing an alias of an open anchor or a too deep nesting."""
        event = self.peek_event()
        if isinstance(event, yaml.AliasEvent):
            self.alias_count += 1
            if self.alias_count > MAX_ALIASES:
                raise self._event_problem(
                    f"too many aliases (more than {MAX_ALIASES})",
                    "use subtrees: or include: to reuse parts of a mission",
                )
            if event.anchor in self._open_anchors:
                raise self._event_problem(
                    f"the alias *{event.anchor} refers to the node that contains it",
                    "recursive YAML structures are not allowed",
                )
            return super().compose_node(parent, index)
        if len(self._open_anchors) >= MAX_NESTING:
            raise self._event_problem(
                f"the YAML nesting is deeper than {MAX_NESTING} levels",
                "flatten the structure; use subtrees: to split a deep tree",
            )
        self._open_anchors.append(getattr(event, "anchor", None) or "")
        try:
            return super().compose_node(parent, index)
        finally:
            self._open_anchors.pop()

    def construct_object(self, node: Node, deep: bool = False) -> Any:
        """Construct one node; a value its standard tag cannot hold is a problem at its place."""
        try:
            return super().construct_object(node, deep)
        except (ValueError, TypeError, AttributeError, OverflowError) as exc:
            raise UserError(
                Problem(
                    f"invalid {_tag_name(node.tag)} value: {exc}",
                    self.filename,
                    *_mark(node),
                    hint="quote the value to keep it as text",
                )
            ) from None

    def construct_bounded_int(self, node: ScalarNode) -> int:
        """An integer, refused where it stands when no float can hold it: a 400-digit number would
        overflow the first float it meets (a time limit, a speed) far from its line. Smaller ones
        go on to the range checks of the setting or parameter they are given to."""
        value: int = self.construct_yaml_int(node)
        if abs(value) > MAX_INT:
            digits = len(str(abs(value)))
            raise UserError(
                Problem(
                    f"a number of {digits} digits is too large (no number here goes past about 1.8e308)",
                    self.filename,
                    *_mark(node),
                    hint="write it with an exponent (1e30) if you mean a float, or quote it to keep it as text",
                )
            )
        return value

    def construct_timestamp_as_text(self, node: ScalarNode) -> str:
        """Dates and times stay text: missions have no use for them, and bad dates must not crash."""
        return str(self.construct_scalar(node))

    def construct_mapping(self, node: MappingNode, deep: bool = False) -> MarkedDict:
        """A mapping as a :class:`MarkedDict`; a duplicate or unhashable key is a problem at its place."""
        own = sum(1 for key_node, _ in node.value if key_node.tag != _STANDARD_TAG + "merge")
        self.flatten_mapping(node)  # merged pairs ('<<: *base') first, then the mapping's own
        merged = len(node.value) - own
        result = MarkedDict()
        result.mark = _mark(node)
        written: set[Any] = set()
        for i, (key_node, value_node) in enumerate(node.value):
            key = self.construct_object(key_node, deep=True)
            try:
                hash(key)
            except TypeError:
                self.problems.append(Problem("a mapping key must be a plain value", self.filename, *_mark(key_node)))
                continue
            if i >= merged and key in written:
                first = result.marks[key]
                self.problems.append(
                    Problem(
                        f"duplicate key '{key}'",
                        self.filename,
                        *_mark(key_node),
                        hint=f"'{key}' is already given at line {first[0]}; YAML would silently keep only one",
                    )
                )
                continue
            if i >= merged:
                written.add(key)  # a key of its own overrides a merged one; twice is a mistake
            result[key] = self.construct_object(value_node, deep=True)
            result.marks[key] = _mark(key_node)
            result.value_marks[key] = _mark(value_node)
        return result

    def construct_sequence(self, node: SequenceNode, deep: bool = False) -> MarkedList:
        """A sequence as a :class:`MarkedList`."""
        result = MarkedList(self.construct_object(child, deep=True) for child in node.value)
        result.mark = _mark(node)
        result.marks = [_mark(child) for child in node.value]
        return result

    def construct_undefined(self, node: Node) -> Any:
        """A tag that is not a standard one: refused (no Python objects, no custom types)."""
        raise UserError(
            Problem(
                f"the tag {_tag_name(node.tag)} is not allowed",
                self.filename,
                *_mark(node),
                hint="mission and maze files are plain data: remove the '!' tag",
            )
        )


def _tag_name(tag: str) -> str:
    """A tag as it is written: ``!!python/object`` rather than ``tag:yaml.org,2002:python/object``."""
    return "!!" + tag[len(_STANDARD_TAG) :] if tag.startswith(_STANDARD_TAG) else tag


_Loader.add_constructor(_STANDARD_TAG + "map", _Loader.construct_mapping)
_Loader.add_constructor(_STANDARD_TAG + "seq", _Loader.construct_sequence)
_Loader.add_constructor(_STANDARD_TAG + "timestamp", _Loader.construct_timestamp_as_text)
_Loader.add_constructor(_STANDARD_TAG + "int", _Loader.construct_bounded_int)
_Loader.add_constructor(None, _Loader.construct_undefined)


_FastLoader: type[_Loader] | None = None
if yaml.__with_libyaml__:
    from yaml._yaml import CParser

    class _LibyamlLoader(CParser, _Loader):
        """:class:`_Loader` on libyaml's scanner and parser (C, a tenth of the Python one's cost), under
        the same composer, checks and constructor: the same data and marks from a file both accept."""

        check_node = Composer.check_node
        get_node = Composer.get_node
        get_single_node = Composer.get_single_node

        def __init__(self, stream: str, filename: str) -> None:
            CParser.__init__(self, stream)
            Composer.__init__(self)
            SafeConstructor.__init__(self)
            Resolver.__init__(self)
            self._start(filename)

    _FastLoader = _LibyamlLoader


def _expanded_size(root: Node) -> tuple[int, int] | None:
    """(distinct nodes, nodes once every alias is expanded), or None when a node contains itself.

    Each node is visited once (sizes are memoised), so nested aliases cost linear time.
    """
    size: dict[int, int] = {}
    on_path: set[int] = set()
    stack: list[tuple[Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        if isinstance(node, ScalarNode):
            size[id(node)] = 1
            continue
        children = node.value if isinstance(node, SequenceNode) else [v for kv in node.value for v in kv]
        if children_done:
            on_path.discard(id(node))
            size[id(node)] = 1 + sum(size[id(child)] for child in children)
            continue
        if id(node) in size:
            continue
        on_path.add(id(node))
        stack.append((node, True))
        for child in children:
            if id(child) in on_path:
                return None
            if id(child) not in size:
                stack.append((child, False))
    return len(size), size[id(root)]


def loads_yaml(text: str, filename: str = "<input>") -> Any:
    """Parse YAML text safely; raise :class:`UserError` with file:line:col on any problem.

    A text read a second time (a grader loading a mission in four worlds, a sweep's workers) is kept
    parsed, and each later read gets a deep copy, ten times quicker than a parse (callers may change
    what they get). A text read once, as by ``thymio-bt run``, is parsed and never copied."""
    if len(text) > CACHED_TEXT:
        return _parse(text, filename)
    key = hash((text, filename))
    if key not in _READ_ONCE:
        _READ_ONCE[key] = None
        if len(_READ_ONCE) > KEPT_TEXTS:
            _READ_ONCE.popitem(last=False)
        return _parse(text, filename)
    return copy.deepcopy(_parsed(text, filename))


#: texts up to this many characters are kept parsed once read twice (the last 64 of them)
CACHED_TEXT = 256 * 1024
KEPT_TEXTS = 64
#: hashes of the texts read, oldest first (OrderedDict's popitem is one step under the GIL)
_READ_ONCE: OrderedDict[int, None] = OrderedDict()


def _parse(text: str, filename: str) -> Any:
    """The parse of ``text``: by libyaml when it is there and the text is of :func:`_plain_ascii`; a text
    libyaml refuses is parsed again by the Python parser, whose messages and places users see."""
    if _FastLoader is not None and _plain_ascii(text):
        try:
            return _composed(_FastLoader(text, filename), filename)
        except UserError:
            pass
    try:
        loader = _Loader(text, filename)  # the reader rejects control characters right here
    except yaml.reader.ReaderError as exc:
        pos = exc.position
        line, col = text.count("\n", 0, pos) + 1, pos - text.rfind("\n", 0, pos)
        char = f"U+{exc.character:04X}" if isinstance(exc.character, int) else repr(exc.character)
        raise UserError(
            Problem(
                f"invalid YAML: the character {char} is not allowed",
                filename,
                line,
                col,
                hint="remove it (YAML files may not hold control characters)",
            )
        ) from None
    return _composed(loader, filename)


def _composed(loader: _Loader, filename: str) -> Any:
    """The document ``loader`` parses, composed, checked (aliases) and constructed."""
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        sizes = _expanded_size(node)
        if sizes is None:  # composing already refuses an alias inside its own anchor; kept as a guard
            raise UserError(
                Problem(
                    "an alias refers to the node that contains it",
                    filename,
                    *_mark(node),
                    hint="recursive YAML structures are not allowed",
                )
            )
        if sizes[1] - sizes[0] > MAX_ALIAS_EXPANSION:
            raise UserError(
                Problem(
                    f"the aliases expand to too many nodes ({sizes[1]:,} from {sizes[0]:,} written)",
                    filename,
                    *_mark(node),
                    hint="aliases of aliases multiply; use subtrees: or include: to reuse parts of a mission",
                )
            )
        data = loader.construct_document(node)
    except yaml.MarkedYAMLError as exc:
        raise UserError(_syntax_problem(exc, filename)) from None
    except yaml.YAMLError as exc:
        raise UserError(Problem(f"invalid YAML: {exc}", filename)) from None
    finally:
        loader.dispose()
    if loader.problems:
        raise UserError(loader.problems)
    return data


def _plain_ascii(text: str) -> bool:
    """Whether ``text`` holds only what libyaml and the Python parser read alike: printable ASCII with no
    tab, ``?``, ``!`` or empty value inside ``{...}`` or ``[...]``. Fuzzing found libyaml counting
    columns after a byte-order mark differently, taking tabs inside lines, a ``?`` inside brackets and
    tags ending in a comma where the Python parser refuses them, and placing an empty value after the
    spaces that follow its colon (``tests/test_yamlio.py`` holds the rest to the same data, marks and
    errors).

    >>> _plain_ascii("walls: [{from: [0, 0], to: [1, 0]}]"), _plain_ascii("a: [b?]"), _plain_ascii("a: {b: }")
    (True, False, False)
    """
    return (
        text.isascii()
        and "\t" not in text
        and "?" not in text
        and "!" not in text
        and _NON_PRINTABLE.search(text) is None
        and _EMPTY_IN_BRACKETS.search(text) is None
    )


_NON_PRINTABLE = yaml.reader.Reader.NON_PRINTABLE
_EMPTY_IN_BRACKETS = re.compile(r":\s*[,\]}]")

_parsed = functools.lru_cache(maxsize=KEPT_TEXTS)(_parse)  # never changed: loads_yaml hands out copies


def _syntax_problem(exc: yaml.MarkedYAMLError, filename: str) -> Problem:
    """A YAML syntax error at its place; where the parser was inside something, the hint says so."""
    mark = exc.problem_mark or exc.context_mark
    line, col = (mark.line + 1, mark.column + 1) if mark else (0, 0)
    hint = "check indentation, colons and quotes on this line"
    if "'\\t'" in str(exc.problem):
        hint = "indent with spaces: YAML does not allow tabs for indentation"
    context = exc.context_mark
    if exc.context and context is not None and (context.line + 1, context.column + 1) != (line, col):
        what = exc.context.removeprefix("while ")
        hint = f"{what} that starts at line {context.line + 1}, column {context.column + 1}: {hint}"
    return Problem(f"invalid YAML: {exc.problem or exc.context}", filename, line, col, hint=hint)


def load_yaml(path: str | Path, what: str = "mission") -> Any:
    """Read and parse a YAML file of kind ``what`` (see :mod:`thymio_bt.inputs.reading`: only a regular file,
    up to its cap); a missing, special, huge or unreadable file is a :class:`UserError`."""
    return loads_yaml(read_text(path, what), str(path))
