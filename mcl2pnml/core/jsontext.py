"""The one reader of our JSON inputs, and where a value stands in their text.

Every JSON file a command reads (a world, a vehicle model, a fault file, an
autopilot mapping, a vehicle script, a certificate) goes through
:func:`load_json`: JSON as RFC 8259 says it, no NaN or Infinity (Python's
json reads them, and NaN passes every bound), no key given twice in one
object (Python's json keeps the last silently: a second ``"primitives"``
would drop the first), a UTF-8 byte order mark at the start ignored (RFC
8259 lets a reader ignore it; Windows editors write one). Each fault is one
message at its line and column, wherever the text stops (after its last
newline, an empty file, a file of blanks).

A file is checked on the parsed value, but a fault must be shown where the
user wrote it. :func:`locator` walks a text that has parsed already, as
JSON reads it, and records where each value starts, by its path (keys and
indices from the root).
"""
from __future__ import annotations

import json
from typing import Any, Callable, Iterable

from mcl2pnml.core.errors import EXCERPT_WIDTH, Location, Mcl2PnmlError, text_location, visible
from mcl2pnml.core.files import json_fault

_BLANK = " \t\r\n"
_DECODER = json.JSONDecoder()

Path = tuple  # keys (str) and indices (int) from the root
#: A UTF-8 byte order mark, as a decoded text starts with it.
BOM = "\ufeff"


def offsets(text: str, twice: list[tuple[Path, int, int]] | None = None) -> dict[Path, int]:
    """The offset in ``text`` where each value starts, by its path; ``text`` is valid JSON
    (but for keys given twice, each appended to ``twice`` as its path and the offsets of
    its two keys)."""
    found: dict[Path, int] = {}
    # an explicit stack, not recursion: a file nested thousands deep has parsed
    # (Python's json recurses in C) and must not overflow here
    stack: list[tuple[Path, int]] = [((), _skip(text, 0))]
    while stack:
        path, i = stack.pop()
        found[path] = i
        if text[i] not in "{[":
            continue
        children = []
        opening, closing = text[i], "}" if text[i] == "{" else "]"
        i = _skip(text, i + 1)
        index = 0
        keys: dict[str, int] = {}
        while text[i] != closing:
            if opening == "{":
                at = i
                key, i = json.decoder.scanstring(text, i + 1)
                if twice is not None and key in keys:
                    twice.append((path + (key,), keys[key], at))
                keys[key] = at
                i = _skip(text, i, _BLANK + ":")
                child: Path = path + (key,)
            else:
                child, index = path + (index,), index + 1
            children.append((child, i))
            _, i = _DECODER.raw_decode(text, i)
            i = _skip(text, i, _BLANK + ",")
        stack.extend(reversed(children))
    return found


def _skip(text: str, i: int, chars: str = _BLANK) -> int:
    while i < len(text) and text[i] in chars:
        i += 1
    return i


def locator(text: str, filename: str) -> Callable[[Iterable], Location]:
    """``where(path)``: the location of the value at ``path`` (its nearest located ancestor's)."""
    starts = offsets(text)
    lines = text.split("\n")

    def where(path: Iterable) -> Location:
        path = tuple(path)
        while path not in starts and path:
            path = path[:-1]
        at = starts.get(path)
        if at is None:
            return Location(filename)
        line, column = _line_column(text, at)
        return Location(filename, line, column, lines[line - 1][:column + EXCERPT_WIDTH])
    return where


def dotted(path: Iterable) -> str:
    """A JSON path as the messages write it: ``primitives.KeepDepth.band``, ``safe_state[1]``
    (a key's characters that are not printable escaped, a key over 80 characters cut)."""
    out = ""
    for part in path:
        part = part if isinstance(part, int) else visible(part[:80])
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else part)
    return out or "the file"


class _Twice(Exception):
    """A key given twice in one object (raised while parsing, located after)."""


class _Constant(str):
    """NaN, Infinity or -Infinity where the file has it: refused once the file has parsed."""


def _unique(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    obj = dict(pairs)
    if len(obj) != len(pairs):
        raise _Twice
    return obj


def load_json(text: str, filename: str, what: str) -> Any:
    """The value of a JSON input (see the module's documentation); a text that is not
    JSON, holds NaN or Infinity or a key twice is one message at its line and column
    saying it is not ``what`` (``"an autopilot mapping"``)."""
    text = without_bom(text)
    if not text.strip():
        raise Mcl2PnmlError(f"not {what}: the file is empty" if not text else
                            f"not {what}: the file holds only blanks", Location(filename, 1, 1))
    try:
        data = json.loads(text, object_pairs_hook=_unique, parse_constant=_Constant)
    except json.JSONDecodeError as e:
        # a file cut short: said as such, where it stops
        ends = "the file ends too soon: " if not text[e.pos:].strip() else ""
        raise Mcl2PnmlError(f"not {what}: {ends}{e.msg}",
                            text_location(filename, text, e.lineno, e.colno)) from None
    except _Twice:
        twice: list[tuple[Path, int, int]] = []
        offsets(text, twice)
        path, first, second = min(twice, key=lambda t: t[2])
        line, column = _line_column(text, first)
        raise Mcl2PnmlError(
            f"{dotted(path)}: the key {json.dumps(path[-1])[:80]} is given twice (first at "
            f"{line}:{column}), and JSON would keep only the last: give it once",
            text_location(filename, text, *_line_column(text, second))) from None
    except (ValueError, RecursionError) as e:
        raise Mcl2PnmlError(f"not {what}: {json_fault(e)}", Location(filename)) from None
    constant = first_constant(data)
    if constant is not None:
        path, name = constant
        raise Mcl2PnmlError(f"{dotted(path)}: {name} is not a number",
                            locator(text, filename)(path))
    return data


def _line_column(text: str, at: int) -> tuple[int, int]:
    """The line and column (from 1) of offset ``at`` in ``text``."""
    return text.count("\n", 0, at) + 1, at - (text.rfind("\n", 0, at) + 1) + 1


def parse_located(text: str, filename: str, what: str) -> tuple[Any, Callable[[Iterable], Location]]:
    """A configuration file's JSON (:func:`load_json`) and its locator (:func:`locator`)."""
    data = load_json(text, filename, what)
    return data, locator(without_bom(text), filename)


def without_bom(text: str) -> str:
    """``text`` without the UTF-8 byte order mark it may start with (the readers ignore it)."""
    return text[len(BOM):] if text.startswith(BOM) else text


def first_constant(value: Any) -> tuple[tuple, str] | None:
    """The path of the first NaN or Infinity in a parsed file, and which, or None."""
    stack = [((), value)]
    while stack:
        path, value = stack.pop()
        if isinstance(value, _Constant):
            return path, str(value)
        items = value.items() if isinstance(value, dict) else \
            enumerate(value) if isinstance(value, list) else ()
        stack.extend(reversed([((*path, k), v) for k, v in items]))
    return None


def check_schema(value: Any, schema: dict[str, Any], where: Callable[[Iterable], Location],
                 prefix: tuple = (), what: str = "a valid file") -> None:
    """``value`` against the JSON Schema ``schema``: the first fault, at its line and column
    (``where`` of its path), or nothing. ``prefix`` is the path of ``value`` in its file;
    ``what`` says what the file should have been."""
    # jsonschema, 0.16 s (python -X importtime): only when a file is checked against its
    # schema, never on the CLI's start, which imports this module
    from jsonschema import Draft202012Validator
    from jsonschema.exceptions import best_match

    try:
        error = best_match(Draft202012Validator(schema).iter_errors(value))
        if error is None:
            return
        path = at = tuple(error.absolute_path)
        message = error.message
        if error.validator == "additionalProperties":
            valid = sorted(error.schema.get("properties", {}))
            message = message.replace("Additional properties are not allowed ",
                                      "unknown setting ")
            message += "; valid: " + ", ".join(valid)
            # shown where the first unknown setting is, as a world file's is
            at += tuple(key for key in error.instance if key not in valid)[:1]
        elif "propertyNames" in error.absolute_schema_path:    # a bad name: where it is
            at += (error.instance,)
        elif error.validator == "enum":
            message = f"{json.dumps(error.instance)[:80]} is not one of " + ", ".join(
                map(str, error.validator_value))
    except RecursionError as e:   # a value nested a little less deep than json reads: its repr
        raise Mcl2PnmlError(f"not {what}: {json_fault(e)}",
                            Location(where(()).file)) from None
    raise Mcl2PnmlError(f"{dotted(prefix + path)}: {message[:300]}", where(at))
