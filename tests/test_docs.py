"""The project's own description: docs/model.md is current, nothing points outside the
repository (a clone has nothing beside it), and every shell command the README and docs/ show
still runs.

Commands are read from the documents' code blocks (fenced, or indented by four spaces); a line
continued with a backslash is one command, and `a && b` is two. Checked:

- every `herringbone ...` command parses: it is run with `--help` appended, which argparse
  answers (exit 0) only once every option before it has been read and converted;
- every `python SCRIPT.py ...` of the repository answers `--help`;
- a command shown after a `$ ` prompt with the lines it prints is run for real, and prints
  them; so is every command of CHEAP with arguments (running text names a command by its two
  words) and no placeholder (an upper-case word).

The command line's own parser decides what a command means, so this file names no option.
The Python examples of the README and the pages PYTHON_EXAMPLES names run too, statement by
statement from another folder, and give the numbers they show (`# [2427.9, 2349.6]`).
"""
from __future__ import annotations

import ast
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import MODELS

from herringbone.arguments import COMPILED_METHODS
from herringbone.model.document import with_generated_tables

ROOT = MODELS.parent
# What pointed outside the repository once (the notes beside the checkout); spelt in pieces so
# that this file does not name them itself. docs/model.md is their home now.
OUTSIDE = ("../" + "shared", "MODEL" + ".md", "NOTES" + ".md")


def test_model_document_lists_every_parameter_as_the_package_has_it():
    text = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    assert text == with_generated_tables(text), (
        "docs/model.md section 12 is out of date: run "
        "`python -m herringbone.model.document docs/model.md`")


def test_nothing_points_outside_the_repository():
    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    if tracked.returncode != 0:  # not a git checkout (an unpacked source archive)
        return
    offenders = []
    for name in tracked.stdout.split():
        path = ROOT / name
        if path.suffix in (".py", ".md", ".toml", ".txt", ".c", ".h", ".sh") and path.is_file():
            text = path.read_text(encoding="utf-8", errors="replace")
            if any(mark in text for mark in OUTSIDE):
                offenders.append(name)
    assert not offenders, f"these files point outside the repository: {offenders}"


DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def test_every_list_of_the_compiled_methods_names_them_all():
    """A line of the documents that names the compiled integrator's methods as choices (both
    `dop853` and `radau` in code) names every one that arguments.py allows, so that a method
    added to the package is not left out where a user reads what to choose."""
    offenders = []
    for document in DOCUMENTS:
        for number, line in enumerate(document.read_text(encoding="utf-8").splitlines(), 1):
            named = set(re.findall(r"`([a-z0-9]+)`", line))
            if {"dop853", "radau"} <= named and not set(COMPILED_METHODS) <= named:
                offenders.append(f"{document.relative_to(ROOT)}:{number}")
    assert not offenders, f"these lines leave out a method of {COMPILED_METHODS}: {offenders}"


def _herringbone() -> list[str]:
    """The installed `herringbone` command: its console script beside this Python, or else
    its entry point called by this Python."""
    script = Path(sys.executable).with_name("herringbone")
    if script.is_file():
        return [str(script)]
    from importlib.metadata import entry_points

    (entry,) = entry_points(group="console_scripts", name="herringbone")
    module, function = entry.value.split(":")
    return [sys.executable, "-c", f"import sys; from {module} import {function}; "
            f"sys.argv[0] = 'herringbone'; sys.exit({function}())"]


HERRINGBONE = _herringbone()
CHEAP = {"scenes", "info", "campbell"}  # subcommands that finish within seconds
PLACEHOLDER = re.compile(r"\b[A-Z][A-Z_0-9.]*[A-Z]\b")  # SCENE, OUT.fmu's OUT, HOST, ...
FENCE = re.compile(r"^```")
INLINE = re.compile(r"`((?:herringbone|python3?) [^`]+)`")  # a command in running text


def code_blocks(text: str) -> list[list[str]]:
    """The lines of each code block: fenced (any language but toml, python, yaml, cpp and
    text, which hold no commands) or indented."""
    blocks: list[list[str]] = []
    fenced: list[str] | None = None
    language = ""
    indented: list[str] = []
    for line in text.splitlines():
        if FENCE.match(line):
            if fenced is None:
                fenced, language = [], line.strip("`").strip()
            else:
                if language not in ("toml", "python", "yaml", "cpp", "text"):
                    blocks.append(fenced)
                fenced = None
            continue
        if fenced is not None:
            fenced.append(line)
        elif line.startswith("    ") and line.strip():
            indented.append(line[4:])
        elif indented and line.strip():
            blocks.append(indented)
            indented = []
    if indented:
        blocks.append(indented)
    return blocks


def commands(document: Path) -> list[tuple[list[str], list[str]]]:
    """(argv, the lines shown after it) for each command of the document's code blocks and
    running text; the lines shown only where the command follows a `$ ` prompt."""
    text = document.read_text(encoding="utf-8")

    def split(command: str) -> list[str]:
        try:
            return shlex.split(command, comments=True)
        except ValueError as error:  # name the culprit: this runs while pytest collects
            raise ValueError(f"{document.name}: {command!r}: {error} (a shell command "
                             "here; put prose and output in a text block)") from None

    found = [(split(span), []) for span in INLINE.findall(text)]
    for block in code_blocks(text):
        joined: list[str] = []
        for line in block:
            if joined and joined[-1].endswith("\\"):
                joined[-1] = joined[-1][:-1] + " " + line.strip()
            else:
                joined.append(line)
        prompted = any(line.startswith("$ ") for line in joined)
        for number, line in enumerate(joined):
            if prompted and not line.startswith("$ "):
                continue
            shown = []
            if prompted:
                following = joined[number + 1:]
                ends = [i for i, next_line in enumerate(following) if next_line.startswith("$ ")]
                shown = following[:ends[0] if ends else len(following)]
            for part in line.removeprefix("$ ").split("&&"):
                argv = split(part)
                if argv:
                    found.append((argv, shown))
    return found


def documented(kind: str) -> list[tuple[str, list[str], list[str]]]:
    """(where, argv, shown) for the documented commands of a kind, `herringbone` or `python`,
    each once."""
    found = []
    seen = set()
    for document in DOCUMENTS:
        for argv, shown in commands(document):
            if (tuple(argv), tuple(shown)) in seen:
                continue
            seen.add((tuple(argv), tuple(shown)))
            program = Path(argv[0]).name
            if kind == "herringbone" and program == "herringbone":
                found.append((document.name, ["herringbone", *argv[1:]], shown))
            elif kind == "python" and program.startswith("python") and len(argv) > 1 \
                    and argv[1].endswith(".py") and (ROOT / argv[1]).is_file():
                found.append((document.name, argv, shown))
    return found


def unbracketed(arguments: list[str]) -> list[str]:
    """The arguments without the optional ones a synopsis shows in brackets."""
    kept, depth = [], 0
    for argument in arguments:
        depth += argument.count("[")
        if depth == 0:
            kept.append(argument)
        depth -= argument.count("]")
    return kept


def run(argv: list[str], cwd: Path, timeout: float = 120.0) -> subprocess.CompletedProcess:
    return subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=timeout)


def _identifier(entry) -> str:
    return f"{entry[0]}: {shlex.join(entry[1])}"[:90]




def _parses_alone(argv: list[str]) -> bool:
    """Whether `argv` is a command that `--help` appended can check: not a synopsis naming no
    command (`herringbone COMMAND ...`), not a quoted message (`herringbone sweep: ...`), not
    --version (which answers before --help), and not one that names an FMU to build first
    (--through-fmu is checked as it is parsed: tests/cli has it)."""
    if len(argv) < 2:
        return True
    return not (argv[1].isupper() or argv[1].endswith(":") or "--version" in argv
                or "--through-fmu" in argv)


HERRINGBONE_COMMANDS = [entry for entry in documented("herringbone") if _parses_alone(entry[1])]
PYTHON_COMMANDS = documented("python")


def test_the_documents_show_commands_of_every_kind():
    subcommands = {argv[1] for _, argv, _ in HERRINGBONE_COMMANDS if len(argv) > 1}
    assert len(HERRINGBONE_COMMANDS) >= 10 and len(subcommands) >= 5, subcommands
    assert any(argv[1] == "build_fmu.py" for _, argv, _ in PYTHON_COMMANDS)


@pytest.mark.parametrize("entry", [e for e in HERRINGBONE_COMMANDS if not e[2]], ids=_identifier)
def test_documented_herringbone_command_parses(entry):
    _, argv, _ = entry
    completed = run([*HERRINGBONE, *unbracketed(argv[1:]), "--help"], cwd=ROOT)
    assert completed.returncode == 0, completed.stderr
    assert completed.stdout.startswith("usage:")


@pytest.mark.parametrize("entry", [e for e in HERRINGBONE_COMMANDS if e[2]], ids=_identifier)
def test_documented_output_is_what_the_command_prints(entry, tmp_path):
    _, argv, shown = entry
    completed = run([*HERRINGBONE, *argv[1:]], cwd=tmp_path)
    printed = (completed.stdout + completed.stderr).splitlines()
    for line in shown:
        assert line in printed, f"{line!r} not among {printed}"


@pytest.mark.parametrize("entry", [e for e in HERRINGBONE_COMMANDS
                                   if len(e[1]) > 2 and e[1][1] in CHEAP and not e[2]
                                   and not any(PLACEHOLDER.search(a) for a in e[1])],
                         ids=_identifier)
def test_cheap_documented_command_runs(entry, tmp_path):
    _, argv, _ = entry
    completed = run([*HERRINGBONE, *argv[1:]], cwd=tmp_path)
    assert completed.returncode == 0, completed.stderr


@pytest.mark.parametrize("script", sorted({argv[1] for _, argv, _ in PYTHON_COMMANDS}))
def test_documented_script_answers_help(script):
    completed = run([sys.executable, script, "--help"], cwd=ROOT)
    assert completed.returncode == 0, completed.stderr
    assert "usage" in completed.stdout.lower()


def test_readme_links_lead_to_files_of_the_repository():
    """The README is read outside the site (where mkdocs checks the links): its own check."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    targets = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text)
    local = [t for t in targets if "://" not in t]
    assert len(local) >= 10
    assert [t for t in local if not (ROOT / t).exists()] == []


# A file of the checkout as a page names it: under one of the repository's top folders, to
# its last letter or digit (a sentence's full stop is not part of it)
CHECKOUT_PATH = re.compile(r"(?<![\w./-])(?:tests|benchmarks|examples|models|docs|fmu_src|\.ci)"
                           r"/[\w./-]*\w")


def test_every_file_a_page_names_is_in_the_repository():
    """A reader follows a page's paths in the checkout (the hosts page's C host, the
    benchmarks, the scenes): each must be there."""
    named = {path for page in DOCUMENTS
             for path in CHECKOUT_PATH.findall(page.read_text(encoding="utf-8"))}
    assert len(named) >= 50
    assert sorted(path for path in named if not (ROOT / path).exists()) == []


# The pages whose Python examples a reader pastes as they stand: how many of each page's
# blocks (```python), run in order in one namespace, as the page builds them up.
# The hosts page's example runs the FMU that `build-fmu` writes (scene_fmu builds it here).
PYTHON_EXAMPLES = {"README.md": 1, "docs/api.md": 1, "docs/steady-state.md": 4,
                   "docs/hosts.md": 1, "docs/monodromy.md": 1}
BUILT_FMUS = {"dist/reference-fmi2.fmu": "reference"}
# an example's line that shows what its expression gives: `expression   # [1.5, -2.25] unit`
SHOWN = re.compile(r"#\s*\[(?P<numbers>[-+0-9.e, ]+)\]")


def python_blocks(page: Path) -> list[str]:
    """The page's ```python blocks, in order."""
    return re.findall(r"^```python\n(.*?)^```", page.read_text(encoding="utf-8"), re.S | re.M)


def assert_shown(value, numbers: str, where: str) -> None:
    """`value`, a sequence of numbers, is what the example shows (`numbers`, comma-separated),
    each to half a unit of its last digit shown."""
    shown = numbers.split(",")
    assert len(value) == len(shown), f"{where}: {list(value)} against [{numbers}]"
    for got, text in zip(value, shown):
        text = text.strip()
        decimals = len(text.split(".")[1]) if "." in text else 0
        assert abs(got - float(text)) <= 0.5 * 10.0 ** -decimals, (
            f"{where}: {list(value)} against [{numbers}]")


@pytest.mark.parametrize("page", sorted(PYTHON_EXAMPLES))
def test_a_pages_python_examples_run_and_give_the_numbers_it_shows(page, tmp_path, monkeypatch,
                                                                    scene_fmu):
    """Each statement of the page's examples run in turn, from a folder of the reader's own
    (a shipped scene by its name, an FMU where build-fmu put it), and every expression the
    page shows the numbers of gives those numbers."""
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for k, block in enumerate(python_blocks(ROOT / page)[:PYTHON_EXAMPLES[page]]):
        for path, scene in BUILT_FMUS.items():
            if path in block:
                (tmp_path / path).parent.mkdir(exist_ok=True)
                shutil.copy(scene_fmu(scene), tmp_path / path)
        lines = block.splitlines()
        for statement in ast.parse(block).body:
            where = f"{page}, block {k + 1}, line {statement.lineno}"
            shown = SHOWN.search(lines[statement.end_lineno - 1])
            if isinstance(statement, ast.Expr) and shown:
                value = eval(compile(ast.Expression(statement.value), where, "eval"), namespace)
                assert_shown(value, shown.group("numbers"), where)
            else:
                exec(compile(ast.Module([statement], []), where, "exec"), namespace)


def api_functions() -> dict[str, object]:
    """The functions `import herringbone` gives (herringbone.__all__), the Scene's methods
    that make a scene from another, and the functions of the API page's modules that the
    command line's stability, campbell, build-fmu and --ssp run: what a user calls."""
    import inspect

    import herringbone
    from herringbone.analysis import campbell, stability
    from herringbone.fmu import builder, ssp

    functions = {name: getattr(herringbone, name) for name in herringbone.__all__
                 if inspect.isfunction(getattr(herringbone, name))}
    commands = (stability.stability_chart, campbell.elastic_frequencies, campbell.crossings,
                builder.build_gear_fmu, ssp.build_ssp)
    return {**functions, "Scene.with_parameters": herringbone.Scene.with_parameters,
            "Scene.with_inputs": herringbone.Scene.with_inputs,
            **{f"{function.__module__}.{function.__name__}": function for function in commands}}


@pytest.mark.parametrize("name", sorted(api_functions()))
def test_an_api_functions_docstring_examples_run_and_give_what_they_show(name, tmp_path,
                                                                          monkeypatch):
    """Every function of api_functions has an example in its docstring (what `help()` and the
    API page show), none skipped, and from a folder of the reader's own it prints what the
    docstring says it does (doctest; whitespace between words may differ)."""
    import doctest

    monkeypatch.chdir(tmp_path)
    function = api_functions()[name]
    tests = doctest.DocTestFinder(recurse=False).find(function, name, globs={})
    examples = [example for test in tests for example in test.examples]
    assert any(example.want for example in examples), f"{name}: no example that shows a result"
    assert not any(example.options.get(doctest.SKIP) for example in examples), name
    runner, report = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE), []
    for test in tests:
        runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)
