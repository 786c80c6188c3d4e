"""MCL for Pygments: the lexer that highlights MCL in the docs, in Jupyter and for any
Pygments user (``pygmentize -l mcl``), registered as the ``pygments.lexers`` entry point
``mcl`` (pyproject.toml) for files ``*.mcl``.

Its words are the parser's, read from the grammar as lark analysed it
(:func:`mcl2pnml.language.parser.grammar`), never listed again here:

* a declaration's first word (``const``, ``task``, ``property``...) is a declaration
  keyword, and the name after it what the grammar says it declares: a callable where
  ``(`` follows it, a constant where ``=`` does, else a label (a property's name);
* the reserved words (:data:`~mcl2pnml.language.parser.KEYWORDS`: ``if``, ``parallel``,
  ``timeout``...) are keywords everywhere;
* the other words of the grammar (``never``, ``leads``, ``before``...) are keywords only
  inside the declaration that uses them, from its first word to its ``;``, as the
  parser's contextual lexer reads them: a mission may call a task ``before``. There a
  word that stands where an atom may (``true``, ``false``) is a constant, and so are
  the results (``OK``...); the atoms (``running``...) are
  :data:`~mcl2pnml.language.declared_properties.ATOMS`;
* names, numbers, strings, comments and white space are matched by the grammar's own
  regular expressions, so that what the parser refuses (an unclosed string or comment,
  a character outside MCL) is an error token;
* the task patterns (``AchieveGoal``...) are the template library's
  (:mod:`mcl2pnml.language.library`), a user's templates included.

The table is built when the first lexer is made, not at import: Pygments imports every
plugin lexer whenever it looks up a name it does not know, and only who highlights MCL
pays for lark's analysis of the grammar and the library's loading (0.1 s).
"""
from __future__ import annotations

import re
from collections import defaultdict
from typing import Any

from pygments.lexer import RegexLexer, bygroups, words
from pygments.token import Comment, Keyword, Name, Number, Punctuation, String, Whitespace

from mcl2pnml.core.errors import Mcl2PnmlError

#: The token of each regular terminal of the grammar, by the grammar's name for it.
REGULAR = {"WS": Whitespace, "COMMENT": Comment, "STRING": String.Double,
           "NUMBER": Number}
#: The state a declaration whose own words are keywords only inside it opens.
INSIDE = "declaration"
#: The state of an atom's arguments, names whatever words they are.
ARGUMENTS = "arguments"


class MclLexer(RegexLexer):
    """Pygments' lexer for MCL: docs/mcl.md's missions and docs/properties.md's
    properties."""

    name = "MCL"
    aliases = ["mcl"]
    filenames = ["*.mcl"]
    mimetypes = ["text/x-mcl"]

    @classmethod
    def get_tokendefs(cls) -> dict[str, list]:
        # Pygments builds its table from this at the first lexer made (RegexLexerMeta),
        # so the grammar is read then, not when Pygments imports its plugins
        return token_table()


class _Grammar:
    """What the highlighter reads of the grammar: its literals, its regular terminals,
    and the terminals each rule reaches."""

    def __init__(self) -> None:
        # lark's analysis of the grammar, 40 ms: only where MCL is highlighted
        from mcl2pnml.language.parser import KEYWORDS, grammar
        g = grammar()
        self.reserved = frozenset(KEYWORDS)
        self.literal = {t.name: t.pattern.value for t in g.terminals if t.pattern.type == "str"}
        self.regex = {t.name: t.pattern.to_regexp() for t in g.terminals
                      if t.pattern.type == "re"}
        self.rules: dict[str, list[list[Any]]] = defaultdict(list)
        for rule in g.rules:
            self.rules[rule.origin.name].append(list(rule.expansion))
        self.name = self.regex["NAME"]

    def is_word(self, terminal: str) -> bool:
        return terminal in self.literal and re.fullmatch(self.name, self.literal[terminal]) \
            is not None

    def reach(self, origin: str) -> tuple[set[str], set[str]]:
        """The rules and the terminals the rule ``origin`` reaches."""
        seen, todo, found = {origin}, [origin], set()
        while todo:
            for expansion in self.rules[todo.pop()]:
                for symbol in expansion:
                    if symbol.is_term:
                        found.add(symbol.name)
                    elif symbol.name not in seen:
                        seen.add(symbol.name)
                        todo.append(symbol.name)
        return seen, found

    def declarations(self) -> dict[str, list[list[Any]]]:
        """Each kind of declaration (the rule ``declaration``'s alternatives), its rules."""
        kinds = [expansion[0].name for expansion in self.rules["declaration"]]
        return {kind: self.rules[kind] for kind in kinds}

    def atoms(self, origins: set[str]) -> tuple[set[str], set[tuple[str, str]]]:
        """Where an atom may stand (a rule with an alternative led by a name and a literal):
        the words that stand there alone (constants), and the literals around a name-led
        atom's arguments."""
        constants, brackets = set(), set()
        for origin in origins:
            expansions = self.rules[origin]
            led = [e for e in expansions
                   if len(e) > 2 and e[0].name == "NAME" and e[1].name in self.literal]
            if led:
                constants.update(self.literal[e[0].name] for e in expansions
                                 if len(e) == 1 and self.is_word(e[0].name))
                brackets.update((self.literal[e[1].name], self.literal[e[-1].name])
                                for e in led)
        return constants, brackets


def _declared(g: _Grammar, expansions: list[list[Any]]):
    """The token of the name a declaration declares: a callable where ``(`` follows it,
    a constant where ``=`` does, else a label; None where it declares no name."""
    named = [e for e in expansions if len(e) > 2 and e[1].name == "NAME"]
    if not named:
        return None
    after = g.literal.get(named[0][2].name)
    return {"(": Name.Function, "=": Name.Constant}.get(after, Name.Label)


def _words(found) -> Any:
    return words(sorted(found, key=lambda w: (-len(w), w)), prefix=r"\b", suffix=r"\b")


def token_table() -> dict[str, list]:
    """The lexer's states, from the grammar and the template library (the module's
    docstring says how)."""
    # the ATOMS and RESULTS of properties, and the library: only where MCL is highlighted
    from mcl2pnml.language.declared_properties import ATOMS, RESULTS
    g = _Grammar()
    kinds = g.declarations()
    first = {kind: g.literal[rules[0][0].name] for kind, rules in kinds.items()}
    word = {kind: re.escape(w) for kind, w in first.items()}
    every = {g.literal[t] for t in g.literal if g.is_word(t)}
    reached = {kind: g.reach(kind) for kind in kinds}
    contextual = every - g.reserved - set(first.values())
    own = {kind: {g.literal[t] for t in reached[kind][1] if g.is_word(t)} & contextual
           for kind in kinds}
    openers = [kind for kind in kinds if own[kind]]
    ws, name = g.regex["WS"], g.name
    common = [(g.regex[t], token) for t, token in REGULAR.items()]
    punctuation = words(sorted((v for t, v in g.literal.items() if not g.is_word(t)),
                               key=len, reverse=True))
    root = list(common)
    for kind, rules in kinds.items():
        declared, push = _declared(g, rules), (INSIDE,) if kind in openers else ()
        if declared is not None:
            root.append((rf"\b({word[kind]})({ws})({name})",
                         bygroups(Keyword.Declaration, Whitespace, declared), *push))
        root.append((rf"\b{word[kind]}\b", Keyword.Declaration, *push))
    root += [(_words(g.reserved), Keyword),
             (_words(_patterns(name, g.reserved)), Name.Builtin),
             (rf"{name}(?=(?:{ws})?\()", Name.Function),
             (name, Name),
             (punctuation, Punctuation)]
    inside, arguments = list(common), list(common)
    for kind in openers:   # a declaration of its own words ends at its last literal
        ends = {g.literal[e[-1].name] for e in kinds[kind] if e[-1].name in g.literal}
        constants, brackets = g.atoms(reached[kind][0])
        inside += [(words(sorted(ends)), Punctuation, "#pop")]
        for opens, closes in sorted(brackets):   # an atom's arguments are names
            inside += [(rf"({kinds_of})((?:{ws})?)({re.escape(opens)})",
                        bygroups(token, Whitespace, Punctuation), ARGUMENTS)
                       for kinds_of, token in ((_words(ATOMS).get(), Name.Builtin),
                                               (name, Name))]
            arguments.append((re.escape(closes), Punctuation, "#pop"))
        inside += [(_words(constants), Keyword.Constant),
                   (_words(own[kind] - constants), Keyword)]
    inside += [(name, Name), (punctuation, Punctuation)]
    arguments += [(_words(RESULTS), Name.Constant), (name, Name), (punctuation, Punctuation)]
    return {"root": root, INSIDE: inside, ARGUMENTS: arguments}


def _patterns(name: str, reserved: frozenset[str]) -> list[str]:
    """The task patterns of the template library, by every name a task may give them."""
    # the template library, 40 ms: only where MCL is highlighted
    from mcl2pnml.language.library import default_library, Library, template_dirs
    from mcl2pnml.language.template_parser import TemplateKind
    try:
        library = default_library()
    except Mcl2PnmlError:   # a user's template directory is broken: ours still highlight
        library = Library.load(template_dirs()[:1])
    return sorted(n for t in library.unique() if t.kind is TemplateKind.PATTERN
                  for n in t.names if re.fullmatch(name, n) and n not in reserved)
