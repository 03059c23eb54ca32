"""A result file written whole or not at all: every file a command or a build writes (a run's
CSV, a sweep's table, a picture, an FMU, an SSP archive) goes through replace_file, so that a
failure or an interrupt (Ctrl-C) while it is written leaves the file that was there before,
never half a file that reads as a result."""
from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path


def replace_file(target: Path, write: Callable[[Path], object]) -> None:
    """Replace `target` by what `write` writes to the staging path it is given (beside the
    target, with the target's extension, which writers such as matplotlib's read the format
    from); on any error or interrupt the staging file is removed and `target` is left as it
    was. The target's folder must exist."""
    target = Path(target)
    # beside the target, so that os.replace is atomic: a reader never sees half a file
    fd, staging = tempfile.mkstemp(dir=target.parent, prefix=f".{target.stem}.",
                                   suffix=f".partial{target.suffix}")
    os.close(fd)
    try:
        write(Path(staging))
        os.chmod(staging, 0o644)  # mkstemp makes it private; a result is an ordinary file
        os.replace(staging, target)
    except BaseException:
        Path(staging).unlink(missing_ok=True)
        raise
