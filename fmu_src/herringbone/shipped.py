"""The scenes and example FMU scripts that come with the package, and the one resolver that
lets every command take a shipped scene's name where it takes a scene file.

Installed from a wheel, they are package data: `scenes/` (the repository's `models/*.toml`),
`examples/` (the repository's `examples/`: the motor and fan FMU scripts and the
parametric-resonance scene) and `docs/` (the pages a gear FMU carries), put there by
pyproject.toml. In a source checkout (an editable install, or `fmu_src` on the path) they are
read where the repository keeps them.
"""
from __future__ import annotations

import os
import stat
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
_CHECKOUT = PACKAGE.parents[1]  # fmu_src/herringbone -> the repository, in a source checkout


def _folder(packaged: str, in_checkout: str) -> Path:
    folder = PACKAGE / packaged
    return folder if folder.is_dir() else _CHECKOUT / in_checkout


def scenes_folder() -> Path:
    """The shipped scenes (`models/` of the repository)."""
    return _folder("scenes", "models")


def examples_folder() -> Path:
    """The example FMU scripts and scenes (`examples/` of the repository)."""
    return _folder("examples", "examples")


def docs_folder() -> Path:
    """The documentation pages an FMU carries (`docs/` of the repository; in a wheel, those
    pyproject.toml lists)."""
    return _folder("docs", "docs")


def scene_files() -> dict[str, Path]:
    """Name -> file of every shipped scene: models/ first, then the examples' scenes."""
    found: dict[str, Path] = {}
    for folder in (scenes_folder(), examples_folder()):
        for path in sorted(folder.glob("*.toml")) if folder.is_dir() else []:
            found.setdefault(path.stem, path)
    return found


def named_as_typed(scene) -> str:
    """How a user names a loaded Scene: a shipped one by its name ("reference"), as the
    command line takes it, any other by its file."""
    shipped = scene_files().get(scene.name)
    return scene.name if shipped is not None and shipped == Path(scene.source) else \
        str(scene.source)


def is_scene_name(scene) -> bool:
    """Whether `scene` (a str or Path) is written as a bare name: no folder, no suffix."""
    text = str(scene)
    return bool(text) and Path(text).name == text and not Path(text).suffix


def resolve_scene(scene) -> Path:
    """The scene file `scene` means: an existing file as it is; else, if written as a bare name
    ("reference"), the shipped scene of that name; else the path as given (whose loading then
    says that there is no such file; `unreadable` says what a path is that is there but is
    no file to read)."""
    path = Path(scene)
    if not path.is_file() and is_scene_name(scene):
        return scene_files().get(str(scene), path)
    return path


# what stat's file type says a path is, where it is neither a regular file nor a folder
_FILE_KINDS = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
               (stat.S_ISFIFO, "a named pipe (FIFO)"), (stat.S_ISSOCK, "a socket"))


def unreadable(path: Path) -> str | None:
    """Why `path`, which is there, is no scene file to read ("not a regular file: a character
    device (a symbolic link to /dev/zero)", which load_scene calls "no such scene file"), or
    None: where it is a regular file or a folder, or not there at all (load_scene says so in
    its own words, a shipped scene's name among them). The command line asks before it
    loads a scene (cli/common.scene_of)."""
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        if path.is_symlink():
            return f"a symbolic link to {os.readlink(path)}, which does not exist"
        return None
    except OSError as error:  # a name over the file system's limit, a link loop, no access
        return f"cannot be looked up: {error.strerror or error}"
    if stat.S_ISREG(mode) or stat.S_ISDIR(mode):
        return None
    kind = next((name for test, name in _FILE_KINDS if test(mode)), "of another kind")
    link = f" (a symbolic link to {os.readlink(path)})" if path.is_symlink() else ""
    return f"not a regular file: {kind}{link}"


def headline(path: Path) -> str:
    """What a scene file's header comment says it is: its first sentence, from the comment
    lines above everything else but a line that says how to run it ("Run: …"), cut at a word
    to HEADLINE_WIDTH characters ('' without a header)."""
    lines = []
    try:
        with open(path, encoding="utf-8") as file:
            for line in file:
                line = line.strip()
                if not line.startswith("#"):
                    break
                text = line.lstrip("#").strip()
                if not text.startswith("Run:"):
                    lines.append(text)
    except (OSError, UnicodeDecodeError):
        return ""
    words = " ".join(lines)
    end = words.find(". ")
    sentence = words if end < 0 else words[:end + 1]
    if len(sentence) <= HEADLINE_WIDTH:
        return sentence
    return sentence[:HEADLINE_WIDTH - 1].rsplit(" ", 1)[0] + " …"


# the characters of a scene's headline in `herringbone scenes`: its line within a terminal's 120
HEADLINE_WIDTH = 96


def scene_list() -> list[str]:
    """`herringbone scenes`: one line per shipped scene, by name, its name and its headline."""
    files = scene_files()
    width = max(map(len, files), default=0)
    return [f"{name:<{width}}  {headline(files[name])}" for name in sorted(files)]
