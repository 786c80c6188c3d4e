"""PNML is untrusted input: entity bombs, external entities, huge and deep files.

The reader's parser (``mcl2pnml/pnml/reader.py``, ``_parse_xml``) resolves no
entity, loads no DTD, touches no network and keeps libxml2's limits on
(no ``huge_tree``): 10 MB per text node, 256 levels of nesting. Each hostile
file must give one located error, through the API and through the CLI
(exit 2, no traceback), quickly and in bounded memory; peak memory is read
from ``VmHWM`` in a fresh interpreter, so that the test's own pages do not count.
"""
from __future__ import annotations

import http.server
import re
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from mcl2pnml.core.errors import Mcl2PnmlError, PnmlError
from mcl2pnml.io.pnml.reader import parse_pnml

from helpers import DATA, run_cli

HEAD = (b'<?xml version="1.0"?>\n'
        b'<pnml xmlns="http://www.pnml.org/version-2009/grammar/pnml">\n'
        b'<net id="n" type="http://www.pnml.org/version-2009/grammar/ptnet"><page id="pg">\n')
TAIL = b"</page></net>\n</pnml>\n"
SECRET = "s3cr3t-never-to-be-read"
#: Peak memory a hostile file may cost, well above the 320 MB a 100 MB file
#: measured (its bytes, and its lines only when an error is located).
MEMORY_LIMIT_KB = 700_000

BILLION_LAUGHS = (b'<?xml version="1.0"?>\n<!DOCTYPE pnml [\n <!ENTITY l0 "ha">\n'
                  + b"".join(b' <!ENTITY l%d "%s">\n' % (i, b"&l%d;" % (i - 1) * 10)
                             for i in range(1, 10))
                  + b"]>\n" + HEAD[22:] + b'<place id="p"><name><text>&l9;</text></name>'
                  + b"</place>\n" + TAIL)


def load_measured(path: Path) -> tuple[str, int]:
    """What loading ``path`` in a fresh interpreter gives, and its peak memory in kB."""
    script = ("import sys\nfrom mcl2pnml.core.errors import Mcl2PnmlError\n"
              "from mcl2pnml.io.pnml.reader import read_pnml\n"
              "try:\n    net = read_pnml(sys.argv[1])\n"
              "    print(f'loaded {len(net.places)} places')\n"
              "except Mcl2PnmlError as e:\n    print(e)\n"
              "hwm = [l for l in open('/proc/self/status') if l.startswith('VmHWM')]\n"
              "print(hwm[0].split()[1])\n")
    out = subprocess.run([sys.executable, "-c", script, str(path)], capture_output=True,
                         text=True, timeout=600)  # a hang guard, not a timing
    assert out.returncode == 0 and not out.stderr, out.stderr
    *message, peak = out.stdout.strip().splitlines()
    return "\n".join(message), int(peak)


def assert_one_cli_error(path: Path, message: str, commands=("validate", "analyze")) -> None:
    """Exit 2, no traceback, the reader's message once, located; ``analyze`` says nothing
    else, ``validate`` may add what the official grammar finds, and its verdict line."""
    located = rf"{re.escape(str(path))}:\d+:\d+: "
    for command in commands:
        out = run_cli(command, path)
        assert out.returncode == 2, (command, out.stdout, out.stderr)
        assert "Traceback" not in out.stderr
        assert len(re.findall(located + r"[^\n]*" + re.escape(message), out.stderr)) == 1, \
            out.stderr
        if command == "analyze":
            assert len(re.findall(located, out.stderr)) == 1, out.stderr


# -- entities and the network ----------------------------------------------------------

def test_billion_laughs_is_refused_before_any_expansion(tmp_path):
    path = tmp_path / "laughs.pnml"
    path.write_bytes(BILLION_LAUGHS)
    message, peak = load_measured(path)
    assert message.startswith(f"{path}:2:1: document type declarations are refused")
    assert peak < MEMORY_LIMIT_KB
    assert_one_cli_error(path, "document type declarations are refused")


class _Recorder(http.server.BaseHTTPRequestHandler):
    requests: list[str] = []

    def do_GET(self):  # noqa: N802 (the name http.server calls)
        _Recorder.requests.append(self.path)
        self.send_response(200)
        self.end_headers()
        self.wfile.write(b'<!ENTITY x "REMOTE-CONTENT">')

    def log_message(self, *args):
        pass


@pytest.fixture
def server():
    """An HTTP server on localhost that records every request it gets."""
    _Recorder.requests = []
    httpd = http.server.HTTPServer(("127.0.0.1", 0), _Recorder)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_port}"
    httpd.shutdown()
    httpd.server_close()


def test_external_entities_dtds_and_includes_are_never_fetched(tmp_path, server):
    secret = tmp_path / "secret.txt"
    secret.write_text(SECRET)
    documents = {
        "file_entity.pnml": f'<!DOCTYPE pnml [<!ENTITY x SYSTEM "{secret.as_uri()}">]>',
        "http_entity.pnml": f'<!DOCTYPE pnml [<!ENTITY x SYSTEM "{server}/entity">]>',
        "parameter_entity.pnml": f'<!DOCTYPE pnml [<!ENTITY % p SYSTEM "{server}/p"> %p;]>',
        "external_dtd.pnml": f'<!DOCTYPE pnml SYSTEM "{server}/pnml.dtd">',
    }
    for name, doctype in documents.items():
        data = (b'<?xml version="1.0"?>\n' + doctype.encode() + b"\n" + HEAD[22:]
                + b'<place id="p"><name><text>&x;</text></name></place>\n' + TAIL)
        with pytest.raises(PnmlError) as info:
            parse_pnml(data, name)
        assert str(info.value).startswith(f"{name}:2:1: document type declarations are refused")
        assert SECRET not in str(info.value) and "REMOTE-CONTENT" not in str(info.value)
    # an XInclude is an element like any other unknown one, never followed: refused by
    # the strict reading, at its place, for its namespace; skipped by the forgiving one
    data = (HEAD + b'<place id="p"><name><text>x</text></name>'
            b'<include xmlns="http://www.w3.org/2001/XInclude" href="' + secret.as_uri().encode()
            + b'" parse="text"/></place>\n' + TAIL)
    with pytest.raises(PnmlError) as info:
        parse_pnml(data, "xinclude.pnml")
    assert str(info.value).startswith("xinclude.pnml:4:42: <include> in the namespace "
                                      "'http://www.w3.org/2001/XInclude' in place 'p'")
    assert SECRET not in str(info.value)
    net = parse_pnml(data, "xinclude.pnml", lenient=True)
    assert [p.name for p in net.places] == ["x"]
    assert _Recorder.requests == []  # nothing reached the network


# -- size and depth --------------------------------------------------------------------

def test_a_100_mb_text_node_is_refused_in_bounded_memory(tmp_path):
    path = tmp_path / "huge_text.pnml"
    with path.open("wb") as f:
        f.write(HEAD + b'<place id="p"><name><text>')
        for _ in range(100):
            f.write(b"a" * 1_000_000)
        f.write(b"</text></name></place>\n" + TAIL)
    assert path.stat().st_size > 100_000_000
    message, peak = load_measured(path)
    assert message.startswith(f"{path}:4:") and "Text node too long" in message, message
    assert peak < MEMORY_LIMIT_KB, f"peak {peak:,} kB"
    assert_one_cli_error(path, "Text node too long")


def test_100_000_nested_elements_are_refused(tmp_path):
    path = tmp_path / "deep.pnml"
    path.write_bytes(HEAD + b"<page>" * 100_000 + b"</page>" * 100_000 + TAIL)
    message, peak = load_measured(path)
    assert message.startswith(f"{path}:4:") and "Excessive depth in document" in message
    assert peak < MEMORY_LIMIT_KB
    assert_one_cli_error(path, "Excessive depth in document")


@pytest.mark.slow
def test_a_million_places_load_correctly(tmp_path):
    """76 MB of places loads whole (a net that size is legitimate); prints the peak."""
    path = tmp_path / "million.pnml"
    with path.open("wb") as f:
        f.write(HEAD)
        for i in range(1_000_000):
            f.write(b'<place id="p%d"><initialMarking><text>1</text></initialMarking>'
                    b"</place>\n" % i)
        f.write(TAIL)
    message, peak = load_measured(path)
    print(f"\n{path.stat().st_size:,} bytes, {message}: peak {peak:,} kB")
    assert message == "loaded 1000000 places"
    assert peak < 4_000_000  # the lxml tree is ~1.5 GB: linear in the file, not more


# -- nets that break the rules: one located error each ------------------------------------

@pytest.mark.parametrize("name, message", [
    ("dangling_arc.pnml", "is not a place or transition of this net"),
    ("duplicate_id.pnml", "duplicate id"),
    ("negative_marking.pnml", "initialMarking must be a natural number"),
    ("truncated.pnml", "Premature end of data"),
    ("entity_bomb.pnml", "document type declarations are refused"),
])
def test_bad_nets_through_the_cli(name, message):
    path = DATA / "pnml" / "invalid" / name
    with pytest.raises(Mcl2PnmlError, match=message):
        parse_pnml(path.read_bytes(), name)
    assert_one_cli_error(path, message, ("analyze",))  # test_cli.py validates them all


@pytest.mark.parametrize("written", ["&quot;q&#x22;&#34;&#x0022;", "a&#9;b", "a&#x20;b"])
def test_an_id_written_with_references_is_located_where_it_is_written(written):
    # a fault found once the file is read is located by searching the file for its id:
    # the id as the file writes it, with character references and predefined entities
    data = ('<pnml xmlns="http://www.pnml.org/version-2009/grammar/pnml">\n'
            '  <net id="n" type="http://www.pnml.org/version-2009/grammar/ptnet"><page id="g">\n'
            f'    <place id="{written}"/>\n'
            f'    <transition id="{written}"/>\n'
            '  </page></net>\n</pnml>').encode()
    with pytest.raises(Mcl2PnmlError) as info:
        parse_pnml(data, "f.pnml")
    errors = getattr(info.value, "errors", None) or [info.value]
    assert all(e.location.line in (3, 4) and e.location.column == 5 for e in errors), \
        str(info.value)
