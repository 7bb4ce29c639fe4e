#!/usr/bin/env python3
"""Writes docs/reference/scenario-format.md from the scenario schema (pydantic) and
docs/reference/node-parameters.md from the nodes' parameter tables, so the references cannot
drift from what run_scenario and the nodes accept.

    python scripts/gen_docs.py           # rewrite the page
    python scripts/gen_docs.py --check   # exit 1 if a committed page differs from its source

Every section is one model of the schema, walked from the top-level Scenario: each key with its
type, default, constraints (ge / le / gt / lt, lengths, patterns) and description. Descriptions
come from the model's docstring, the field's description and the comments beside and above the
field in the schema's source. Runs with the project's venv (source scripts/ensure_env.sh); no ROS.
"""
from __future__ import annotations

import argparse
import ast
import difflib
import functools
import inspect
import io
import json
import os
import sys
import textwrap
import tokenize
import typing
from typing import Any, Dict, List, Optional, Tuple

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGE = os.path.join(ROOT, "docs", "reference", "scenario-format.md")
PARAMETERS_PAGE = os.path.join(ROOT, "docs", "reference", "node-parameters.md")
TOPICS_PAGE = os.path.join(ROOT, "docs", "reference", "topics.md")
# The Python packages' sources, after whatever is installed: the venv alone is enough (no ROS).
_SRC = os.path.join(ROOT, "ros_ws", "src")
sys.path += [os.path.join(_SRC, d) for d in sorted(os.listdir(_SRC)) if os.path.isdir(os.path.join(_SRC, d, d))]

from scenario_format.scenario import Scenario as SCHEMA  # noqa: E402  the one place that names the schema
import sim_contract.node_params as NODE_PARAMS  # noqa: E402  the nodes' parameter tables
import sim_contract.topics as TOPICS  # noqa: E402  the topic contract
from scenario_runner.autopilot_law import NODE_TABLE as AUTOPILOT_TABLE  # noqa: E402  the example autopilot's

import annotated_types  # noqa: E402
from pydantic import BaseModel  # noqa: E402
from pydantic.fields import FieldInfo  # noqa: E402
from pydantic_core import PydanticUndefined  # noqa: E402


# ---------------------------------------------------------------------------------------------
# Source comments: the schema documents most keys in comments beside or above the field.

@functools.lru_cache(maxsize=None)
def _field_comments(cls: type) -> Dict[str, str]:
    """{field name: its comments} for the fields a class itself declares: the full-line comments
    directly above the field and the comment at the end of its line(s)."""
    try:
        source = inspect.getsource(cls)
    except (OSError, TypeError):
        return {}
    source = textwrap.dedent(source)
    lines = source.splitlines()
    comments: Dict[int, str] = {}
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            comments[tok.start[0]] = tok.string.lstrip("#").strip()
    out: Dict[str, str] = {}
    body = ast.parse(source).body[0].body
    for node in body:
        if not (isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name)):
            continue
        above: List[str] = []
        n = node.lineno - 1
        while n >= 1 and n in comments and lines[n - 1].lstrip().startswith("#"):
            above.insert(0, comments[n])
            n -= 1
        beside = [comments[i] for i in range(node.lineno, node.end_lineno + 1)
                  if i in comments and not lines[i - 1].lstrip().startswith("#")]
        text = " ".join(above + beside).strip()
        if text:
            out[node.target.id] = text
    return out


def _declaring_class(model: type, name: str) -> type:
    for klass in model.__mro__:
        if name in klass.__dict__.get("__annotations__", {}):
            return klass
    return model


def _docstring(cls: type) -> str:
    return inspect.cleandoc(cls.__dict__.get("__doc__") or "")


# ---------------------------------------------------------------------------------------------
# Markdown helpers

def _num(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    text = f"{value:g}"
    if "e" in text:
        mant, exp = text.split("e")
        text = f"{mant}e{int(exp)}"
    return text


def _text(s: str) -> str:
    """Plain text (a comment or docstring) for a Markdown table cell or paragraph: code spans kept,
    characters Markdown would take as markup escaped outside them."""
    parts = s.split("`")
    for i in range(0, len(parts), 2):
        p = parts[i].replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
        parts[i] = p.replace("*", "\\*").replace("|", "\\|").replace("_", "\\_")
    if len(parts) % 2 == 0:   # an unmatched backtick: keep it literal
        parts[-2] = parts[-2] + "\\`" + parts.pop()
    return "`".join(parts)


def _code(value: str) -> str:
    return "``" + value + "``" if "`" in value else "`" + value + "`"


def _literal(value: Any) -> str:
    """A value as it is written in the YAML file."""
    if value is None:
        return "null"
    if isinstance(value, (bool, int, float)):
        return _num(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_literal(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_literal(v)}" for k, v in value.items()) + "}"
    return str(value)


# ---------------------------------------------------------------------------------------------
# Types and constraints

def _constraints(metadata) -> List[str]:
    out: List[str] = []
    for m in metadata:
        if isinstance(m, FieldInfo):
            out += _constraints(m.metadata)
        elif isinstance(m, annotated_types.Ge):
            out.append(f"≥ {_num(m.ge)}")
        elif isinstance(m, annotated_types.Gt):
            out.append(f"> {_num(m.gt)}")
        elif isinstance(m, annotated_types.Le):
            out.append(f"≤ {_num(m.le)}")
        elif isinstance(m, annotated_types.Lt):
            out.append(f"< {_num(m.lt)}")
        elif isinstance(m, annotated_types.MinLen):
            out.append(f"length ≥ {m.min_length}")
        elif isinstance(m, annotated_types.MaxLen):
            out.append(f"length ≤ {m.max_length}")
        elif getattr(m, "pattern", None) is not None:
            out.append(f"pattern {_code(m.pattern)}")
    # "length ≥ 1, length ≤ 253" reads better as "length 1 to 253", and "length 3" when equal
    lo = next((c for c in out if c.startswith("length ≥ ")), None)
    hi = next((c for c in out if c.startswith("length ≤ ")), None)
    if lo and hi:
        words = f"length {lo[9:]}" if lo[9:] == hi[9:] else f"length {lo[9:]} to {hi[9:]}"
        out = [words] + [c for c in out if c not in (lo, hi)]
    return out


_SCALARS = {float: "number", int: "integer", bool: "boolean", str: "string", type(None): "null"}


def _is_model(t) -> bool:
    return isinstance(t, type) and issubclass(t, BaseModel)


def _type(t, anchors: Dict[type, str]) -> str:
    """A type annotation in words; nested constraints in brackets; models as links to their section."""
    origin, args = typing.get_origin(t), typing.get_args(t)
    if origin is typing.Annotated:
        inner, meta = args[0], args[1:]
        cons = _constraints(meta)
        return _type(inner, anchors) + (f" ({', '.join(cons)})" if cons else "")
    if origin is typing.Union:
        members = [a for a in args if a is not type(None)]
        words = " or ".join(_type(a, anchors) for a in members)
        return words + (" or null" if len(members) < len(args) else "")
    if origin is typing.Literal:
        return "one of " + ", ".join(_code(_literal(a).strip('"')) for a in args)
    if origin in (list, List):
        return "list of " + _type(args[0], anchors) if args else "list"
    if origin in (dict, Dict):
        return f"mapping of {_type(args[0], anchors)} to {_type(args[1], anchors)}" if args else "mapping"
    if t is Any:
        return "any"
    if _is_model(t):
        return f"[{t.__name__}](#{anchors[t]})"
    if t in _SCALARS:
        return _SCALARS[t]
    return _code(getattr(t, "__name__", str(t)))


def _models_in(t) -> List[type]:
    if _is_model(t):
        return [t]
    out: List[type] = []
    for a in typing.get_args(t):
        out += [m for m in _models_in(a) if m not in out]
    return out


def _walk(top: type) -> List[Tuple[type, str]]:
    """(model, the key path where it first appears) in depth-first order from the top model."""
    seen: Dict[type, str] = {top: ""}
    order: List[type] = [top]

    def visit(model: type, path: str):
        for name, field in model.model_fields.items():
            key = f"{path}.{name}" if path else name
            for sub in _models_in(field.annotation):
                if sub in seen:
                    continue
                sub_path = key + ("[]" if _is_listed(field.annotation, sub) else "")
                seen[sub] = sub_path
                order.append(sub)
                visit(sub, sub_path)

    visit(top, "")
    return [(m, seen[m]) for m in order]


def _is_listed(t, model: type) -> bool:
    """True when the model appears inside a list in this annotation."""
    origin, args = typing.get_origin(t), typing.get_args(t)
    if origin in (list, List):
        return model in _models_in(args[0])
    return any(_is_listed(a, model) for a in args)


def _default(field: FieldInfo) -> str:
    if field.is_required():
        return "required"
    if field.default_factory is not None:
        value = field.default_factory()
    else:
        value = field.default
    if isinstance(value, BaseModel):
        return "its defaults"
    if value is PydanticUndefined:
        return ""
    return _code(_literal(value))


def _config_words(model: type) -> List[str]:
    cfg = model.model_config
    words = []
    if cfg.get("extra") == "forbid":
        words.append("unknown keys are errors")
    if cfg.get("strict"):
        words.append("values are not converted (the text \"1\" is not a number, 1 is not true)")
    if cfg.get("allow_inf_nan") is False:
        words.append("NaN and infinite numbers are refused")
    return words


# ---------------------------------------------------------------------------------------------
# The page

def _module_docstring(model: type) -> List[str]:
    """The schema module's docstring: prose as paragraphs, the indented example as a YAML block."""
    doc = inspect.getdoc(sys.modules[model.__module__]) or ""
    out: List[str] = []
    in_code = False
    for line in doc.splitlines():
        if line.startswith("    "):
            if not in_code:
                out += ["```yaml"]
                in_code = True
            out.append(line[4:])
        elif in_code and not line.strip():
            out.append("")
        else:
            if in_code:
                while out and not out[-1]:
                    out.pop()
                out += ["```", ""]
                in_code = False
            out.append(_text(line) if line.strip() else "")
    if in_code:
        while out and not out[-1]:
            out.pop()
        out.append("```")
    return out


def render(top: type = SCHEMA) -> str:
    models = _walk(top)
    anchors = {m: m.__name__.lower() for m, _ in models}
    top_rules = _config_words(top)
    lines = [
        "<!-- Generated by scripts/gen_docs.py from the scenario schema: do not edit by hand.",
        "     Rewrite with `python scripts/gen_docs.py`; the test suite checks it is current. -->",
        "",
        "# Scenario format reference",
        "",
        f"Every key a scenario file may hold, read from the schema `{top.__module__}.{top.__name__}` "
        "(pydantic) that `run_scenario` validates with. The [scenario format](../scenario-format.md) "
        "page explains the keys with an annotated example; this page lists each key's type, default "
        "and limits; a key without a description here is explained there.",
        "",
    ]
    if top_rules:
        lines += ["In every section: " + "; ".join(top_rules) + ". A key whose default is "
                  "\"required\" must be given; \"null\" means the key is left out.", ""]
    lines += ["## Schema summary", ""] + _module_docstring(top) + [""]
    for model, path in models:
        title = _code(path) if path else "top level"
        lines += [f"## {title}: {model.__name__} {{#{anchors[model]}}}", ""]
        doc = _docstring(model)
        if doc:
            lines += [_text(" ".join(p.split())) + "\n" for p in doc.split("\n\n")]
        extra = [w for w in _config_words(model) if w not in top_rules]
        if extra:
            lines += ["Here also: " + "; ".join(extra) + ".", ""]
        lines += ["| key | type | default | limits | description |", "|---|---|---|---|---|"]
        for name, field in model.model_fields.items():
            key = field.alias or name
            comments = _field_comments(_declaring_class(model, name))
            desc = " ".join(d for d in (field.description, comments.get(name)) if d)
            lines.append("| " + " | ".join([
                _code(key), _type(field.annotation, anchors), _default(field),
                ", ".join(_constraints(field.metadata)), _text(desc)]) + " |")
        lines.append("")
    return "\n".join(lines).rstrip("\n") + "\n"


def node_tables():
    """{executable: its parameter table} of every node with one."""
    return {**NODE_PARAMS.NODE_TABLES, "autopilot": AUTOPILOT_TABLE + NODE_PARAMS.STEPPING}


def render_node_parameters() -> str:
    """The nodes' parameter tables (sim_contract.node_params), one section a node."""
    lines = [
        "<!-- Generated by scripts/gen_docs.py from sim_contract.node_params: do not edit by hand.",
        "     Rewrite with `python scripts/gen_docs.py`; the test suite checks it is current. -->",
        "",
        "# Node parameters reference",
        "",
        "The ROS parameters of each simulator node, read from the tables the nodes declare them from "
        f"(`{NODE_PARAMS.__name__}`). The runner sets them from the scenario; `ros2 param list / get "
        "/ set` reads and sets them on a running node. A parameter marked *live* may change while the "
        "node runs; the others are fixed at start-up (a change is refused, naming the live ones). "
        "A number outside its range is refused by the node, and by the scenario before any node starts.",
        "",
    ]
    for executable, table in node_tables().items():
        lines += [f"## {_code(table.node)} {{#{executable.replace('_', '-')}}}", "",
                  "| parameter | type | default | range | unit | live | description |",
                  "|---|---|---|---|---|---|---|"]
        for p in table:
            span = (f"{_num(p.lo)} to {_num(p.hi)}" if p.lo is not None else
                    "one of " + ", ".join(_code(c) for c in p.choices) if p.choices else "")
            lines.append("| " + " | ".join([_code(p.name), p.ros_type, "none (used when given)" if p.default is None else _code(json.dumps(p.default)), span, p.unit,
                                            "live" if p.live else "", _text(p.description)]) + " |")
        lines.append("")
    return "\n".join(lines).rstrip("\n") + "\n"


def render_topics() -> str:
    """The topic contract's tables (sim_contract.topics), one section a namespace."""
    lines = [
        "<!-- Generated by scripts/gen_docs.py from sim_contract.topics: do not edit by hand.",
        "     Rewrite with `python scripts/gen_docs.py`; the test suite checks it is current. -->",
        "",
        "# Topic contract reference",
        "",
        f"Every topic of a run, read from the tables the nodes and the runner build their topic names "
        f"from (`{TOPICS.__name__}`). The [topic contract](../topic-contract.md) page explains them. "
        "QoS kinds: " + _text(" ".join(TOPICS.__doc__.split("QoS kinds:")[1].split())),
        "",
    ]
    sections = [("Global", "", TOPICS.GLOBAL_TOPICS),
                ("Per vessel", "/<vessel>/", TOPICS.VESSEL_TOPICS),
                ("Per vessel with azimuth thrusters", "/<vessel>/", TOPICS.THRUSTER_TOPICS),
                ("Per rope", "/<rope>/", TOPICS.ROPE_TOPICS + (TOPICS.END_WRENCH, TOPICS.END_COUPLING,
                                                                  TOPICS.WINCH_TOPIC)),
                ("Per hull contact", "/<contact>/", TOPICS.CONTACT_TOPICS),
                ("Hull interactions (one node for a run's pairs and banks)",
                 f"/{TOPICS.INTERACTIONS}/", TOPICS.INTERACTION_TOPICS)]
    for title, prefix, table in sections:
        lines += [f"## {title}" + (f" ({_code(prefix)})" if prefix else ""), "",
                  "| topic | type | QoS | frame | rate | direction | note |", "|---|---|---|---|---|---|---|"]
        for t in table:
            lines.append("| " + " | ".join([_code(prefix + t.name if prefix else t.name), _code(t.type), t.qos,
                                            _text(t.frame), _text(t.rate), "taken" if t.taken else "published",
                                            _text(t.note)]) + " |")
        lines.append("")
    return "\n".join(lines).rstrip("\n") + "\n"


def pages() -> Dict[str, str]:
    """{path: text} of every generated page."""
    return {PAGE: render(), PARAMETERS_PAGE: render_node_parameters(), TOPICS_PAGE: render_topics()}


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="exit 1 if a committed page differs from its source (writes nothing)")
    args = parser.parse_args(argv)
    stale = 0
    for page, text in pages().items():
        name = os.path.relpath(page, ROOT)
        if args.check:
            try:
                with open(page, encoding="utf-8") as f:
                    have = f.read()
            except FileNotFoundError:
                have = ""
            if have != text:
                sys.stdout.writelines(difflib.unified_diff(have.splitlines(True), text.splitlines(True), name,
                                                           "source"))
                print(f"{name} is out of date: run python scripts/gen_docs.py", file=sys.stderr)
                stale = 1
            else:
                print(f"{name} is current")
            continue
        os.makedirs(os.path.dirname(page), exist_ok=True)
        with open(page, "w", encoding="utf-8") as f:
            f.write(text)
        print(f"wrote {name}")
    return stale


if __name__ == "__main__":
    sys.exit(main())
