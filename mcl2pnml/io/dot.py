"""graphviz's DOT, and the SVG and PNG graphviz renders of it: a drawing written.

What is drawn, and how, is the view's (:mod:`mcl2pnml.view.drawing`); a
drawing reaches this module as its DOT text, which the caller makes, as
PNML's positions come from the caller (:class:`~mcl2pnml.io.formats.SaveOptions`).
Here are what makes DOT a format: how a node's id is named in it, and
that id read back from what graphviz writes (:func:`node_name`,
:func:`node_id`); the text written, or rendered by graphviz's ``dot``
program, whole or not at all, with one message when ``dot`` is missing.
"""
from __future__ import annotations

from pathlib import Path

import graphviz

from mcl2pnml.core.settings import SettingError
from mcl2pnml.core.files import atomic_write_bytes, atomic_write_text
from mcl2pnml.core.net import Net


def node_name(node_id: str) -> str:
    """A node's name in DOT: its id, unless DOT would read that id as something else.

    In an edge ``a:b`` is node ``a``, port ``b``; ``<...>`` is an HTML string
    (markup graphviz renders, images it reads from disk included); a
    backslash or a quote can end a quoted name early; graphviz keeps names
    that start with ``%`` for its anonymous nodes. Such an id is named
    ``~x`` and its UTF-8 in hex, which :func:`node_id` reads back; an id that
    starts with ``~x`` is encoded too, so that an encoded name is never a real id.
    """
    if (any(c in node_id for c in ':\\"') or node_id.startswith(("%", _ENCODED))
            or (node_id.startswith("<") and node_id.endswith(">"))):
        return _ENCODED + node_id.encode().hex()
    return node_id


def node_id(name: str) -> str:
    """The id of the node named ``name`` in DOT (the inverse of :func:`node_name`)."""
    if name.startswith(_ENCODED):
        try:
            return bytes.fromhex(name[len(_ENCODED):]).decode()
        except ValueError:      # a copy of a place (``NAME~3``), not a node of the net
            return ""
    return name


_ENCODED = "~x"


#: How to get graphviz's ``dot`` program, for the message when it is missing.
INSTALL_DOT = ("install graphviz (apt-get install graphviz, dnf install graphviz, "
               "brew install graphviz, or https://graphviz.org/download/)")


def dot_missing(setting: str, without: str) -> SettingError:
    """The one message when ``setting`` needs graphviz's ``dot`` program and it is not on
    the PATH: what is missing, how to install it, and (``without``) what works without it."""
    return SettingError(setting, f"graphviz's 'dot' program is not installed (no 'dot' on "
                                 f"the PATH): {INSTALL_DOT}; {without}")


def to_image(drawing: str, fmt: str) -> bytes:
    """The drawing (its DOT text) rendered by graphviz's ``dot`` in ``fmt`` (svg, png...)."""
    try:
        return graphviz.pipe("dot", fmt, drawing.encode())
    except graphviz.ExecutableNotFound:
        raise dot_missing("fmt", "the formats pnml, tina, lola and dot (the source) "
                                 "work without it") from None


def to_svg(drawing: str) -> bytes:
    """The drawing (its DOT text) as SVG."""
    return to_image(drawing, "svg")


def to_png(drawing: str) -> bytes:
    """The drawing (its DOT text) as PNG."""
    return to_image(drawing, "png")


def write_image(drawing: str, path: str | Path, fmt: str) -> None:
    """The drawing (its DOT text) rendered in ``fmt`` to ``path``, whole or not at all."""
    atomic_write_bytes(path, to_image(drawing, fmt))


def write_dot(net: Net, path: str | Path, *, drawing: str) -> None:
    """The DOT text of ``net``'s drawing to ``path``, whole or not at all."""
    atomic_write_text(path, drawing)


def write_svg(net: Net, path: str | Path, *, drawing: str) -> None:
    """``net``'s drawing as SVG to ``path``, whole or not at all."""
    write_image(drawing, path, "svg")


def write_png(net: Net, path: str | Path, *, drawing: str) -> None:
    """``net``'s drawing as PNG to ``path``, whole or not at all."""
    write_image(drawing, path, "png")
