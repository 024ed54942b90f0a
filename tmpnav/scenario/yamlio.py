"""Reading YAML safely: the YAML 1.2 core schema, with bounded size, depth and aliases.

PyYAML implements YAML 1.1, where ``1e-3`` is a string (a float needs a dot), ``010`` is
octal 8, ``on``/``no`` are booleans and ``1:30`` is 90. :class:`Yaml12Loader` resolves
plain scalars by the YAML 1.2 core schema instead (null, true/false, decimal, 0o and 0x
integers, floats with or without a dot, .inf, .nan); merge keys (``<<``) still work.

Before anything is built, :func:`read_yaml` streams the parser's events once and refuses
a file nested deeper than ``YAML_MAX_DEPTH``, one whose aliases would expand past the
``yaml_nodes`` cap (a 1.5 KB "billion laughs" file expands exponentially) or an alias to
a collection that contains it. Each event costs O(1), so refusing takes time in
proportion to the file, not to its expansion.
"""

from __future__ import annotations

import re
from typing import Any

import yaml
from yaml.constructor import ConstructorError

from tmpnav.scenario.limits import YAML_MAX_DEPTH, YAML_NODES

INT = "tag:yaml.org,2002:int"
FLOAT = "tag:yaml.org,2002:float"
BOOL = "tag:yaml.org,2002:bool"
NULL = "tag:yaml.org,2002:null"
MERGE = "tag:yaml.org,2002:merge"

_INT = re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$")
_FLOAT = re.compile(
    r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"
)
_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_NULL = re.compile(r"^(?:~|null|Null|NULL|)$")


def _construct_object(loader: Any, node: yaml.Node, deep: bool = False) -> Any:
    """PyYAML's construct_object, with a bad explicitly tagged value (``!!int abc``,
    ``!!timestamp x``, ``!!bool maybe``) as a ConstructorError, not a ValueError."""
    try:
        return yaml.constructor.BaseConstructor.construct_object(loader, node, deep)
    except yaml.YAMLError:
        raise
    except (ValueError, TypeError, KeyError, AttributeError, OverflowError):
        kind = node.tag.rpartition(":")[2]
        raise YamlValueError(
            f"value {node.value!r:.60} tagged !!{kind} is not a valid {kind}", node.start_mark
        ) from None


class Yaml12Loader(yaml.SafeLoader):
    """PyYAML's safe loader with the YAML 1.2 core schema for plain scalars."""

    # its own table, filled below (PyYAML copies the parent's table on the first add otherwise)
    yaml_implicit_resolvers: dict[Any, list[tuple[str, re.Pattern[str]]]] = {}  # noqa: RUF012
    construct_object = _construct_object


for _tag, _regexp, _first in (
    (BOOL, _BOOL, "tTfF"),
    (INT, _INT, "-+0123456789"),
    (FLOAT, _FLOAT, "-+0123456789."),
    (NULL, _NULL, ["~", "n", "N", ""]),
    (MERGE, re.compile(r"^(?:<<)$"), "<"),
):
    Yaml12Loader.add_implicit_resolver(_tag, _regexp, list(_first))


def _construct_int(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> int | float:
    text = str(loader.construct_scalar(node))
    if text.startswith(("0o", "0x")):
        return int(text[2:], 8 if text[1] == "o" else 16)
    try:
        return int(text)
    except ValueError:  # more digits than Python converts (4300): far beyond any float
        return float(text)


def _construct_float(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> float:
    text = str(loader.construct_scalar(node)).lower()
    if text.lstrip("+-") == ".inf":
        return float("-inf") if text.startswith("-") else float("inf")
    if text == ".nan":
        return float("nan")
    return float(text)


Yaml12Loader.add_constructor(INT, _construct_int)
Yaml12Loader.add_constructor(FLOAT, _construct_float)

Yaml12CLoader: type | None = None
if getattr(yaml, "__with_libyaml__", False):

    class _Yaml12CLoader(yaml.CSafeLoader):
        """The same schema on libyaml's parser."""

        yaml_implicit_resolvers = Yaml12Loader.yaml_implicit_resolvers
        yaml_constructors = Yaml12Loader.yaml_constructors
        construct_object = _construct_object

    Yaml12CLoader = _Yaml12CLoader


class YamlValueError(ConstructorError):
    """An explicitly tagged value that its tag's constructor cannot read."""

    def __init__(self, message: str, mark: Any):
        super().__init__(None, None, message, mark)


class YamlLimitError(yaml.YAMLError):
    """A YAML file too deep or too large once its aliases are expanded."""

    def __init__(self, message: str, mark: Any):
        super().__init__(message)
        self.problem = message
        self.problem_mark = mark


def check_expansion(text: str, loader: type = Yaml12Loader) -> None:
    """Refuse a document nested deeper than YAML_MAX_DEPTH, with more than the
    ``yaml_nodes`` cap of values once aliases are expanded, or with a recursive alias.

    Raises YamlLimitError (or the parser's own YAMLError for a syntax error).
    """
    cap = YAML_NODES.value()
    open_counts: list[list[Any]] = []  # [values so far, anchor] per open collection
    sizes: dict[str, int] = {}
    expanded = 0  # values of the document so far, aliases expanded
    for event in yaml.parse(text, Loader=loader):
        if isinstance(event, yaml.CollectionStartEvent):
            if len(open_counts) >= YAML_MAX_DEPTH:
                raise YamlLimitError(
                    f"nested deeper than {YAML_MAX_DEPTH} levels; a scenario needs no more than 6",
                    event.start_mark,
                )
            open_counts.append([1, event.anchor])
            size = 1
        elif isinstance(event, yaml.AliasEvent):
            if any(anchor == event.anchor for _, anchor in open_counts):
                raise YamlLimitError(f"alias *{event.anchor} refers to a collection that contains it", event.start_mark)
            size = sizes.get(event.anchor or "", 1)
            if open_counts:
                open_counts[-1][0] += size
        elif isinstance(event, yaml.ScalarEvent):
            size = 1
            if event.anchor:
                sizes[event.anchor] = 1
            if open_counts:
                open_counts[-1][0] += 1
        elif isinstance(event, yaml.CollectionEndEvent):
            done, anchor = open_counts.pop()
            if anchor:
                sizes[anchor] = done
            if open_counts:
                open_counts[-1][0] += done
            continue
        else:
            continue
        expanded += size
        if expanded > cap:  # stop here: counting on would take time in proportion to the file
            raise YamlLimitError(
                "expands to at least "
                + YAML_NODES.refusal(expanded, "fewer aliases of aliases, or a smaller file", at_least=True),
                event.start_mark,
            )


def read_yaml(text: str) -> tuple[Any, yaml.Node | None]:
    """The data of a one-document YAML text and its node tree (for line numbers).

    The text passes :func:`check_expansion` first. libyaml reads it when it is installed
    (twenty times faster); a text it refuses is read again by the pure-Python reader when
    short, whose messages say more ("expected ',' or ']', but got ':'"). Errors are
    yaml.YAMLError subclasses with a ``problem`` and a ``problem_mark`` when known.
    """
    if Yaml12CLoader is None:
        return _read(text, Yaml12Loader)
    try:
        return _read(text, Yaml12CLoader)
    except YamlLimitError:
        raise
    except yaml.YAMLError:
        if len(text) > EXPLAIN_BELOW:
            raise
    return _read(text, Yaml12Loader)


#: texts shorter than this are read again by the pure-Python reader to explain an error
EXPLAIN_BELOW = 1_000_000


def _read(text: str, loader_class: type) -> tuple[Any, yaml.Node | None]:
    check_expansion(text, loader_class)
    loader = loader_class(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None, None
        tree = _copy_tree(node)  # construction flattens merge keys in place: keep the file's shape
        data = loader.construct_document(node)
    finally:
        loader.dispose()
    return data, tree


def _copy_tree(node: yaml.Node) -> yaml.Node:
    """A copy of the collection nodes (scalars are shared), aliases staying shared."""
    copies: dict[int, yaml.Node] = {}

    def copy(n: yaml.Node) -> yaml.Node:
        if isinstance(n, yaml.ScalarNode):
            return n
        if id(n) in copies:
            return copies[id(n)]
        clone: yaml.Node
        if isinstance(n, yaml.MappingNode):
            clone = yaml.MappingNode(n.tag, [], n.start_mark, n.end_mark, n.flow_style)
            copies[id(n)] = clone
            clone.value = [(copy(k), copy(v)) for k, v in n.value]
        else:
            clone = yaml.SequenceNode(n.tag, [], n.start_mark, n.end_mark, getattr(n, "flow_style", None))
            copies[id(n)] = clone
            clone.value = [copy(v) for v in n.value]
        return clone

    return copy(node)


__all__ = ["ConstructorError", "Yaml12Loader", "YamlLimitError", "YamlValueError", "check_expansion", "read_yaml"]
