"""Where a value stands in a JSON text: a JSON path to a line and a column.

A configuration file of ours (a world, a mapping) is parsed by Python's
``json`` and checked on the parsed value, but a fault must be shown where
the user wrote it. :func:`locator` walks a text that has parsed already,
as JSON reads it, and records where each value starts, by its path (keys
and indices from the root); a key given twice is located where JSON takes
it, the last time.
"""
from __future__ import annotations

import json
from typing import Any, Callable, Iterable

from mcl2pnml.core.errors import Location, Mcl2PnmlError
from mcl2pnml.core.files import json_fault

_BLANK = " \t\r\n"
_DECODER = json.JSONDecoder()

Path = tuple  # keys (str) and indices (int) from the root


def offsets(text: str) -> dict[Path, int]:
    """The offset in ``text`` where each value starts, by its path; ``text`` is valid JSON."""
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
        while text[i] != closing:
            if opening == "{":
                key, i = json.decoder.scanstring(text, i + 1)
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
        line = text.count("\n", 0, at)
        column = at - (text.rfind("\n", 0, at) + 1) + 1
        return Location(filename, line + 1, column, lines[line][:400])
    return where


def dotted(path: Iterable) -> str:
    """A JSON path as the messages write it: ``primitives.KeepDepth.band``, ``safe_state[1]``."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "the file"


def parse_located(text: str, filename: str, what: str) -> tuple[Any, Callable[[Iterable], Location]]:
    """A configuration file's JSON and its locator (:func:`locator`); a file that is not
    JSON, or holds a NaN (Python's json reads one, and NaN passes every bound), is one
    message at its line and column saying it is not ``what``."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise Mcl2PnmlError(f"not {what}: {e.msg}", Location(filename, e.lineno, e.colno)) \
            from None
    except (ValueError, RecursionError) as e:
        raise Mcl2PnmlError(f"not {what}: {json_fault(e)}", Location(filename)) from None
    where = locator(text, filename)
    nan = first_nan(data)
    if nan is not None:
        raise Mcl2PnmlError(f"{dotted(nan)}: NaN is not a number", where(nan))
    return data, where


def first_nan(value: Any) -> tuple | None:
    """The path of the first NaN in a parsed file, or None."""
    stack = [((), value)]
    while stack:
        path, value = stack.pop()
        if isinstance(value, float) and value != value:
            return path
        items = value.items() if isinstance(value, dict) else \
            enumerate(value) if isinstance(value, list) else ()
        stack.extend(reversed([((*path, k), v) for k, v in items]))
    return None


def check_schema(value: Any, schema: dict[str, Any], where: Callable[[Iterable], Location],
                 prefix: tuple = (), what: str = "a valid file") -> None:
    """``value`` against the JSON Schema ``schema``: the first fault, at its line and column
    (``where`` of its path), or nothing. ``prefix`` is the path of ``value`` in its file;
    ``what`` says what the file should have been."""
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
