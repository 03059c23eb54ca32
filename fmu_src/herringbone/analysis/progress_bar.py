"""The one progress bar of every long job (a run, a sweep, a continuation, a stability chart):
tqdm on stderr where it is installed and wanted, else a bar that shows nothing.

A progress bar is a courtesy, not part of the job: where tqdm (the `analysis` extra) is not
installed, the job runs without one and says so in one line on stderr, rather than refusing
to run. The job's results are the same either way.
"""
from __future__ import annotations

import sys
import time

from ..optional import MissingDependency, require

# tqdm's line for a run: simulated seconds done of the total, wall time spent and left
SIMULATED_SECONDS = "{l_bar}{bar}| {n:.3g}/{total:.3g} s simulated [{elapsed}<{remaining}]"
# s between two updates of a bar written to a log or a pipe, where each update stays as a line
# of its own (tqdm's 0.1 s made a log line ten times a second)
LOG_INTERVAL = 10.0


class QuietBar:
    """What the jobs use of a tqdm bar, showing nothing: its count `n`, `update`, `reset`,
    `set_description`, `set_postfix_str`, `refresh`, and use as a context manager."""

    def __init__(self, total=None):
        self.total, self.n, self.postfix = total, 0, ""

    def update(self, amount=1) -> None:
        """Count `amount` more done."""
        self.n += amount

    def reset(self, total=None) -> None:
        """Count from zero again."""
        self.n = 0

    def set_description(self, description: str) -> None:
        """Nothing to show."""

    def set_postfix_str(self, postfix: str = "", refresh: bool = True) -> None:
        """Keep `postfix` (nothing shows it)."""
        self.postfix = postfix

    def refresh(self) -> None:
        """Nothing to redraw."""

    def __enter__(self):
        return self

    def __exit__(self, *exception) -> None:
        return None


def progress_bar(total, description: str, enabled: bool = True, unit: str = "s"):
    """A tqdm bar on stderr over `total` units of work (unit "s": simulated seconds, shown
    with SIMULATED_SECONDS; else whole items, e.g. "point"), or a QuietBar where not
    `enabled`, or where tqdm is not installed (then one line on stderr says so)."""
    if not enabled:
        return QuietBar(total)
    try:
        tqdm = require("tqdm", "the progress bar").tqdm
    except MissingDependency as missing:
        print(f"no progress bar: {missing} (or give --no-progress)", file=sys.stderr)
        return QuietBar(total)
    options = ({"unit_scale": False, "bar_format": SIMULATED_SECONDS} if unit == "s"
               else {"smoothing": 0.0})
    if not redrawn(sys.stderr):
        options["mininterval"] = LOG_INTERVAL
    return tqdm(total=total, unit=unit, desc=description, file=sys.stderr, **options)


class Status:
    """How far the item in hand has got, after a bar's count (tqdm's postfix: "w0_pinion
    17.3 rad/s, 120 points"), for an item that takes long: the count alone stood still at
    "1/2 [00:43<00:43]" over the 467 branch points between 10 and 30 rad/s. Redrawn at the
    bar's own pace (its mininterval: a log gets a line every LOG_INTERVAL s, not one a call)."""

    def __init__(self, bar):
        self.bar, self.shown = bar, time.monotonic()  # the bar was just drawn

    def show(self, status: str) -> None:
        """Put `status` after the count; redraw where the bar's mininterval has passed."""
        self.bar.set_postfix_str(status, refresh=False)
        now = time.monotonic()
        if now - self.shown >= getattr(self.bar, "mininterval", 0.0):
            self.bar.refresh()
            self.shown = now


def redrawn(stream) -> bool:
    """Whether a bar on `stream` redraws its one line in place: on a terminal, and in a
    notebook (whose streams are not terminals, but show a carriage return as one)."""
    isatty = getattr(stream, "isatty", None)
    return bool(isatty and isatty()) or "ipykernel" in sys.modules
