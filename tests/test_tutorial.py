"""docs/tutorial.md is true: every command in it prints what it shows, and every
picture it shows is there (python tests/tutorial.py --update rewrites both)."""
import re

from conftest import ROOT
from tutorial import DOC, main


def test_every_command_prints_what_the_tutorial_shows(capsys):
    stale = main([])
    assert stale == 0, ("docs/tutorial.md no longer matches what its commands print "
                        "(python tests/tutorial.py --update):\n" + capsys.readouterr().out)


def test_every_picture_is_there():
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", DOC.read_text())
    assert len(pictures) >= 5
    for picture in pictures:
        path = DOC.parent / picture
        assert path.is_file() and path.read_bytes().startswith(b"\x89PNG"), picture
    assert (ROOT / "docs" / "interop.md").is_file()
