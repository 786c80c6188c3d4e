"""Below the CLI a bad setting is named as the library names it (``connect``, ``net_id``,
``output``); the CLI prints it as the option typed (``--connect``, ``--net``, ``-o``), the
message as it always was (core.settings.SettingError, cli.option_of)."""
from __future__ import annotations

import ast
import pickle
from pathlib import Path

import pytest

import mcl2pnml
import mcl2pnml.analysis
from mcl2pnml.cli import main
from mcl2pnml.core.files import check_outputs
from mcl2pnml.core.settings import Quoted, SettingError
from mcl2pnml.io.formats import FORMATS
from mcl2pnml.runtime.link import LinkOptions, client_tls

from helpers import ROOT, run_cli

SAUCE = ROOT / "examples" / "sauce.mcl"
MAPPING = ROOT / "examples" / "bridges" / "sim_mapping.json"
#: The CLI's own modules: they alone speak of options.
CLI_MODULES = {"cli.py", "cli_options.py"}
#: The calls whose first argument is a setting's name.
NAMING_A_SETTING = {"OptionError", "SettingError", "dot_missing", "seconds_setting",
                    "read_secret", "parse_size", "size_or_none"}


def _called(call: ast.Call) -> str | None:
    return getattr(call.func, "id", None) or getattr(call.func, "attr", None)


def _texts(node: ast.AST) -> list[str]:
    """The string constants ``node`` may be (both branches of ``a if c else b``)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, ast.IfExp):
        return _texts(node.body) + _texts(node.orelse)
    if isinstance(node, ast.JoinedStr) and node.values:
        return _texts(node.values[0])
    return []


def settings_named(source: str) -> list[str]:
    """Each setting ``source`` names by a string: the first argument of a call of
    :data:`NAMING_A_SETTING`, an output's name given to ``check_outputs``."""
    found = []
    for call in (n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.Call)):
        name = _called(call)
        if name in NAMING_A_SETTING:
            given = call.args[:1] + [k.value for k in call.keywords
                                     if k.arg in ("setting", "option")]
            found += [text for arg in given for text in _texts(arg)]
        elif name == "check_outputs" and call.args:
            found += [text for pair in ast.walk(call.args[0]) if isinstance(pair, ast.Tuple)
                      and pair.elts for text in _texts(pair.elts[0])]
    return found


def options_named(source: str) -> list[str]:
    """The settings of ``source`` spelled as command-line options (``"--connect"``)."""
    return [text for text in settings_named(source) if text.startswith("-")]


def _below_the_cli() -> dict[str, str]:
    """The source of every module of the package but the CLI's, by its path."""
    folders = [Path(mcl2pnml.__file__).parent, *map(Path, mcl2pnml.analysis.__path__)]
    return {str(path): path.read_text(encoding="utf-8") for folder in folders
            for path in sorted(folder.rglob("*.py"))
            if path.name not in CLI_MODULES or path.parent != folders[0]}


def test_no_module_below_the_cli_names_an_option():
    assert options_named('raise SettingError("--x" if a else "y", "m")') == ["--x"]
    assert options_named('check_outputs([("-o", p)], [])') == ["-o"]
    offences = {path: named for path, source in _below_the_cli().items()
                for named in [options_named(source)] if named}
    assert offences == {}


def test_every_setting_named_below_the_cli_is_a_parameter_the_cli_names():
    parameters = {p.name for command in main.commands.values() for p in command.params}
    unknown = {path: names for path, source in _below_the_cli().items()
               for names in [set(settings_named(source)) - parameters] if names}
    assert unknown == {}


def test_a_runtime_setting_error_is_shown_as_its_option(tmp_path):
    cert = tmp_path / "end.pem"
    cert.write_text("x")
    with pytest.raises(SettingError) as refused:
        client_tls(LinkOptions(tls_cert=cert))
    assert refused.value.setting == "tls_cert"
    out = run_cli("run", SAUCE, "--vehicle", f"bridge:{MAPPING}", "--connect", "localhost:7",
                  "--tls-cert", cert)
    assert (out.returncode, out.stdout) == (2, "")
    assert out.stderr == (
        "mcl2pnml run: error: Invalid value for --tls-cert: TLS needs --tls-ca, the authority "
        "that signed the bridge's certificate (--tls-cert and --tls-key are this end's own) "
        "(see 'mcl2pnml run --help')\n")


def test_an_io_setting_error_is_shown_as_its_option(tmp_path):
    net = tmp_path / "n.lola"
    net.write_text("")
    with pytest.raises(SettingError) as refused:
        FORMATS["lola"].read(net, "main")
    assert refused.value.setting == "net_id"
    out = run_cli("analyze", net, "--net", "main")
    assert (out.returncode, out.stdout) == (2, "")
    assert out.stderr == ("mcl2pnml analyze: error: Invalid value for --net: a LoLA file "
                          "holds one net; leave out --net (see 'mcl2pnml analyze --help')\n")


def test_a_core_setting_error_names_the_other_output_as_its_option_too(tmp_path):
    both = tmp_path / "g.json"
    with pytest.raises(SettingError) as refused:
        check_outputs([("output", both), ("graph_json", both)])
    error = refused.value
    assert (error.setting, error.message) == (
        "graph_json", f"'{both}' is also the file of output: give each output a file of its own")
    assert error.worded(str.upper).endswith("the file of OUTPUT: give each output a file of "
                                            "its own")
    again = pickle.loads(pickle.dumps(error))
    assert (again.setting, again.pieces) == (error.setting, error.pieces)
    assert Quoted("output") in error.pieces
    out = run_cli("show", SAUCE, "-o", both, "--graph-json", both)
    assert (out.returncode, out.stdout) == (2, "")
    assert out.stderr == (f"mcl2pnml show: error: Invalid value for --graph-json: '{both}' is "
                          "also the file of -o: give each output a file of its own (see "
                          "'mcl2pnml show --help')\n")
    assert not both.exists()
