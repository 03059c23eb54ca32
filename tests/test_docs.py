"""The project's own description: docs/model.md is current, and nothing points outside the
repository (a clone has nothing beside it)."""
import subprocess

from conftest import MODELS

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
