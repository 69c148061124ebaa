"""The code of README.md and docs/*.md against the code it shows.

Every Python block of a section (the blocks of one `##` section read as one
program, in order, as a reader types them) compiles, uses no name it did not
import or define, calls afford's functions with keywords they take and names
attributes the package has. Every `afford` command line of a shell block
names a subcommand of the build's `afford` and options that subcommand
takes, and every script it runs from the checkout exists.
"""
import ast
import builtins
import inspect
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

import afford

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(os.environ.get("AFFORD_BIN", ROOT / "build" / "bin"))
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
sys.path.insert(0, str(ROOT / "tests" / "docs"))
from mdblocks import blocks  # noqa: E402  (the blocks of a markdown file, shared with tests/docs/run_blocks.py)


def python_sections():
    out = {}
    for path in DOCS:
        for b in blocks(path):
            if b.lang == "python":
                out.setdefault((path.relative_to(ROOT).as_posix(), b.section), []).append((b.start, b.text))
    return out


SECTIONS = python_sections()


class Names(ast.NodeVisitor):
    """The names a program defines and those it reads, with the line of each first read."""

    def __init__(self):
        self.defined, self.read = set(dir(builtins)), {}

    def visit_Name(self, node):
        if isinstance(node.ctx, ast.Load):
            self.read.setdefault(node.id, node.lineno)
        else:
            self.defined.add(node.id)

    def visit_alias(self, node):
        self.defined.add((node.asname or node.name).split(".")[0])

    def visit_FunctionDef(self, node):
        self.defined.add(node.name)
        for a in node.args.args + node.args.kwonlyargs + node.args.posonlyargs:
            self.defined.add(a.arg)
        for a in (node.args.vararg, node.args.kwarg):
            if a:
                self.defined.add(a.arg)
        self.generic_visit(node)

    visit_AsyncFunctionDef = visit_FunctionDef

    def visit_Lambda(self, node):
        for a in node.args.args:
            self.defined.add(a.arg)
        self.generic_visit(node)

    def visit_ClassDef(self, node):
        self.defined.add(node.name)
        self.generic_visit(node)

    def visit_ExceptHandler(self, node):
        if node.name:
            self.defined.add(node.name)
        self.generic_visit(node)


def program(chunks):
    """The section's blocks as one program, each block's lines at their place in the file."""
    lines = []
    for start, text in chunks:
        lines += [""] * (start - 1 - len(lines)) + text.splitlines()
    return "\n".join(lines)


def afford_calls(tree):
    """(line, name, keywords) of each call of afford.NAME(...)."""
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and isinstance(node.func.value, ast.Name) and node.func.value.id == "afford"):
            yield node.lineno, node.func.attr, [k.arg for k in node.keywords if k.arg]


@pytest.mark.parametrize("where", sorted(SECTIONS), ids=lambda w: f"{w[0]}#{w[1]}")
def test_each_python_section_compiles_defines_what_it_uses_and_calls_afford_as_it_is(where):
    path, section = where
    source = program(SECTIONS[where])
    tree = compile(source, path, "exec", ast.PyCF_ONLY_AST)  # a SyntaxError names the file and line
    names = Names()
    names.visit(tree)
    undefined = {n: line for n, line in names.read.items() if n not in names.defined}
    assert not undefined, f"{path}, section {section!r}: " + "; ".join(
        f"line {line}: '{n}' is used but never imported or defined" for n, line in sorted(undefined.items()))
    for line, name, keywords in afford_calls(tree):
        assert hasattr(afford, name), f"{path}:{line}: afford has no '{name}'"
        fn = getattr(afford, name)
        params = inspect.signature(fn).parameters
        if any(p.kind == p.VAR_KEYWORD for p in params.values()):
            continue
        wrong = [k for k in keywords if k not in params]
        assert not wrong, f"{path}:{line}: afford.{name}() takes no {', '.join(wrong)}"


def test_the_checks_find_what_they_are_for():
    # A block that uses afford without importing it, and one that calls afford.run with a keyword it lacks.
    names = Names()
    names.visit(ast.parse("e = afford.run('base')"))
    assert "afford" in names.read and "afford" not in names.defined
    calls = list(afford_calls(ast.parse("import afford\nafford.run('base', stesp=3)")))
    assert calls == [(2, "run", ["stesp"])]
    assert "stesp" not in inspect.signature(afford.run).parameters


def command_lines():
    """(file, line, words) of each `afford ...` command of the shell blocks (continuations joined)."""
    for path in DOCS:
        for b in blocks(path):
            if b.lang not in ("sh", "bash", "console", "shell"):
                continue
            start, text = b.start, b.text
            joined, first = "", None
            for k, line in enumerate(text.splitlines()):
                first = start + k if not joined else first
                joined += line.rstrip("\\").rstrip() + " " if line.rstrip().endswith("\\") else line
                if line.rstrip().endswith("\\"):
                    continue
                yield path.relative_to(ROOT).as_posix(), first, joined
                joined = ""


def words_of(line: str):
    line = line.split(" # ")[0] if " # " in line else line
    try:
        return shlex.split(line, comments=True)
    except ValueError:
        return None


_HELP = {}


def options_of(sub: str) -> set[str] | None:
    """The options `afford SUB --help` lists; None for no such subcommand."""
    if sub not in _HELP:
        r = subprocess.run([str(BIN / "afford"), sub, "--help"], capture_output=True, text=True, timeout=60)
        text = r.stdout + r.stderr
        _HELP[sub] = set(re.findall(r"(--[a-z][a-z0-9-]*)", text)) if r.returncode == 0 else None
    return _HELP[sub]


def afford_commands():
    out = []
    for path, line, text in command_lines():
        for part in re.split(r"&&|\|\||;|\|", text):
            words = words_of(part.strip())
            if not words:
                continue
            while words and ("=" in words[0] and not words[0].startswith("-")):  # VAR=value prefixes
                words = words[1:]
            if words[:3] == ["ip", "netns", "exec"]:  # ip netns exec NAME COMMAND
                words = words[4:]
            elif words[:2] == ["scripts/procs.sh", "exec"]:  # scripts/procs.sh exec GROUP COMMAND
                words = words[3:]
            if words and (words[0] == "afford" or words[0].endswith("build/bin/afford")):
                out.append((path, line, words))
    return out


@pytest.mark.parametrize("path,line,words", afford_commands(), ids=lambda v: str(v) if isinstance(v, int) else None)
def test_each_afford_command_of_the_docs_is_a_subcommand_with_options_it_takes(path, line, words):
    rest = words[1:]
    top = {"--config-dir", "--version", "--help", "-h"}
    while rest and rest[0] in top:
        rest = rest[2:] if rest[0] == "--config-dir" else rest[1:]
    if not rest:
        return
    sub = rest[0]
    if sub.startswith("<") or sub in ("...", "COMMAND", "SUBCOMMAND"):
        return
    options = options_of(sub)
    assert options is not None, f"{path}:{line}: afford has no subcommand '{sub}': {' '.join(words)}"
    for w in rest[1:]:
        if w.startswith("--") and w != "--":
            name = w.split("=")[0]
            assert name in options or name == "--help", \
                f"{path}:{line}: `afford {sub}` takes no {name}: {' '.join(words)}"


def test_every_script_the_docs_run_from_the_checkout_exists():
    missing = []
    for path, line, text in command_lines():
        for w in re.findall(r"(?:^|\s)((?:scripts|bench|tests|tools|examples)/[\w./-]+\.(?:sh|py))", text):
            if not (ROOT / w).exists():
                missing.append(f"{path}:{line}: {w}")
    assert not missing, "\n".join(missing)


KNOWN = {"sh", "bash", "python", "yaml", "text"}  # what tests/docs/run_blocks.py runs, writes or shows


def test_every_block_of_the_docs_runs_or_says_why_not():
    # Each block has a language the runner takes (text: shown output), or a directive that says what to do
    # with it (file, fragment), or `skip` with its reason.
    unmarked = []
    for path in DOCS:
        for b in blocks(path):
            said = dict(b.directives)
            if "skip" in said:
                if not said["skip"]:
                    unmarked.append(f"{path.name}:{b.start - 1}: `skip` without a reason")
            elif b.lang not in KNOWN or b.lang == "yaml" and not {"file", "fragment"} & said.keys():
                unmarked.append(f"{path.name}:{b.start - 1}: language {b.lang or '(none)'!r}, no directive")
    assert not unmarked, "\n".join(unmarked)
