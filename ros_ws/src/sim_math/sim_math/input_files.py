"""Reading input YAML files strictly, the one reader of every input file (ship, rope, cable and
scenario files; ROS-free, yaml only): duplicate mapping keys are errors, every error carries the
line and column, and 1e9 reads as a number.

PyYAML's SafeLoader keeps the last of two equal keys silently: `mass: 1000` followed later
by `mass: 1e30` would load the second without a word. And it follows YAML 1.1, where an
exponent needs a dot ("4.4e+8"): `EA: 4.4e8` would be the string "4.4e8"; here it is the
number, as in YAML 1.2.
"""
from __future__ import annotations

import copy
import hashlib
import math
import re
from typing import Any

import yaml


class YamlInputError(ValueError):
    """A file that is not readable, valid YAML, or has a duplicate key; message without the path.
    line / column (1-based, None if unknown), problem (the message without the position) and,
    for a duplicate key, duplicate_key and first_line let a caller word it its own way."""

    def __init__(self, message: str, line: int | None = None, column: int | None = None, problem: str = "",
                 duplicate_key: Any = None, first_line: int | None = None):
        super().__init__(message)
        self.line, self.column, self.problem = line, column, problem or message
        self.duplicate_key, self.first_line = duplicate_key, first_line


class DuplicateKeyError(yaml.constructor.ConstructorError):
    def __init__(self, node, key, key_node, first_mark):
        super().__init__(f"while reading the mapping starting at line {node.start_mark.line + 1}", node.start_mark,
                         f"duplicate key {key!r} (first given at line {first_mark.line + 1})", key_node.start_mark)
        self.key, self.first_line = key, first_mark.line + 1


class UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that refuses a key given twice in one mapping (merge keys `<<` still work:
    only the mapping's own keys are compared)."""

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    first = seen.get(key)
                except TypeError:  # unhashable key: SafeLoader reports it
                    continue
                if first is not None:
                    raise DuplicateKeyError(node, key, key_node, first)
                seen[key] = key_node.start_mark
        return super().construct_mapping(node, deep=deep)


    def compose_document(self):
        """The document's node graph, refused when its aliases expand it beyond MAX_EXPANDED_NODES
        (a few hundred bytes of nested aliases stand for gigabytes: every reader, and every
        error message quoting the value, would expand them)."""
        node = super().compose_document()
        sizes = {}

        def expanded(n) -> int:
            if id(n) not in sizes:
                sizes[id(n)] = 1  # a node reached again through itself counts once
                if isinstance(n, yaml.SequenceNode):
                    sizes[id(n)] = 1 + sum(expanded(c) for c in n.value)
                elif isinstance(n, yaml.MappingNode):
                    sizes[id(n)] = 1 + sum(expanded(k) + expanded(v) for k, v in n.value)
            return sizes[id(n)]

        if node is not None and expanded(node) > MAX_EXPANDED_NODES:
            raise yaml.composer.ComposerError(None, None, f"its aliases expand it to {expanded(node):,} values "
                                              f"(at most {MAX_EXPANDED_NODES:,}): an alias bomb?", node.start_mark)
        return node


MAX_EXPANDED_NODES = 1_000_000  # values of a document with its aliases expanded (the library's largest: ~2,000)

UniqueKeyLoader.add_implicit_resolver(  # YAML 1.2 floats: 1e9, 4.4e8 (YAML 1.1 wants 4.4e+8)
    "tag:yaml.org,2002:float", re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"))


def describe_yaml_error(exc: yaml.YAMLError) -> str:
    """'line L, column C: problem' of a PyYAML error (1-based, as editors count)."""
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    problem = getattr(exc, "problem", None) or str(exc)
    context = getattr(exc, "context", None)
    text = f"{context}: {problem}" if context and "duplicate key" not in str(problem) else str(problem)
    if mark is not None:
        return f"line {mark.line + 1}, column {mark.column + 1}: {text}"
    return text


def _input_error(exc: yaml.YAMLError) -> YamlInputError:
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    dup = isinstance(exc, DuplicateKeyError)
    return YamlInputError(f"not valid YAML: {describe_yaml_error(exc)}",
                          line=mark.line + 1 if mark is not None else None,
                          column=mark.column + 1 if mark is not None else None,
                          problem=str(getattr(exc, "problem", None) or exc),
                          duplicate_key=exc.key if dup else None, first_line=exc.first_line if dup else None)


# Parsed documents by the SHA-256 of the file's bytes. Why: a run's start reads the same ship
# file many times (the scenario check, every node that models or draws the vessel, the
# interaction check of each pair: 60 reads of 20-30 ms each for six vessels with 15 pairs,
# measured). An edited file is parsed again; each caller gets its own deep copy.
_PARSED: "dict[bytes, Any]" = {}
_PARSED_MAX = 64


def load_yaml(path: str) -> Any:
    """The parsed document of a YAML file; YamlInputError (no path in the message) if it cannot
    be read, is not UTF-8, is not valid YAML, repeats a key, nests deeper than the reader goes
    or expands its aliases beyond MAX_EXPANDED_NODES."""
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as exc:
        raise YamlInputError(f"cannot read: {exc.strerror or exc}") from None
    key = hashlib.sha256(raw).digest()
    if key not in _PARSED:
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise YamlInputError(f"not UTF-8 text: {exc}") from None
        document = loads_yaml(text)
        if len(_PARSED) >= _PARSED_MAX:
            _PARSED.pop(next(iter(_PARSED)))
        _PARSED[key] = document
    return copy.deepcopy(_PARSED[key])


def loads_yaml(text: str) -> Any:
    """As load_yaml for a string (e.g. a ROS parameter holding YAML)."""
    try:
        return yaml.load(text, Loader=UniqueKeyLoader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        raise _input_error(exc) from None
    except RecursionError:
        raise _too_deep() from None


def _too_deep() -> YamlInputError:
    return YamlInputError("not readable: lists or mappings nested deeper than the reader goes (hundreds of levels)")


def first_non_finite(data: Any, path: str = "") -> str | None:
    """Dotted path of the first NaN or infinite float anywhere in a parsed document, else None."""
    if isinstance(data, float) and not math.isfinite(data):
        return path or "(top)"
    if isinstance(data, dict):
        for k, v in data.items():
            found = first_non_finite(v, f"{path}.{k}" if path else str(k))
            if found:
                return found
    elif isinstance(data, (list, tuple)):
        for i, v in enumerate(data):
            found = first_non_finite(v, f"{path}.{i}" if path else str(i))
            if found:
                return found
    return None


__all__ = ["YamlInputError", "DuplicateKeyError", "UniqueKeyLoader", "describe_yaml_error", "load_yaml", "loads_yaml",
           "first_non_finite"]
