"""The progress bar: on a terminal tqdm's pace, in a log a line every LOG_INTERVAL seconds."""
import io
import sys

import numpy as np
import pytest

from herringbone.analysis import progress_bar as bars

pytest.importorskip("tqdm")


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def bar_writes(stream, monkeypatch) -> str:
    """What a bar over 50 points, each done 6 ms after the last, writes to `stream`."""
    import time

    monkeypatch.setattr(sys, "stderr", stream)
    with bars.progress_bar(50, "points", unit="point") as bar:
        for _ in range(50):
            time.sleep(0.006)
            bar.update()
    return stream.getvalue()


def test_a_bar_in_a_log_writes_its_start_and_its_end_only(monkeypatch):
    """0.3 s of work in a log (not a terminal, no notebook): the bar's first and last lines,
    none of tqdm's updates ten times a second in between."""
    monkeypatch.delitem(sys.modules, "ipykernel", raising=False)
    lines = bar_writes(io.StringIO(), monkeypatch).split("\r")
    shown = [line for line in lines if line.strip()]
    assert len(shown) == 2 and "0/50" in shown[0] and "50/50" in shown[-1]


def test_a_bar_on_a_terminal_or_in_a_notebook_keeps_tqdms_pace(monkeypatch):
    """On a terminal, or in a notebook, the bar is redrawn at tqdm's 0.1 s: the 0.3 s of work
    shows in between its first and last lines."""
    monkeypatch.delitem(sys.modules, "ipykernel", raising=False)
    assert bars.redrawn(Terminal()) and not bars.redrawn(io.StringIO())
    monkeypatch.setitem(sys.modules, "ipykernel", object())
    assert bars.redrawn(io.StringIO())
    monkeypatch.delitem(sys.modules, "ipykernel")
    lines = [line for line in bar_writes(Terminal(), monkeypatch).split("\r") if line.strip()]
    assert len(lines) >= 3


class CreepingBranch:
    """A stand-in Continuation that creeps from 10 to 30 rad/s by 0.5 rad/s a point, as the
    reference scene's branch did (467 points between 10 and 30 rad/s) while the bar's count
    of requested values stood at 1/2."""

    def __init__(self):
        from types import SimpleNamespace

        self.grid, self.unit = np.array([10.0, 30.0]), 20.0
        self.axis = SimpleNamespace(name="w0_pinion", evaluations=0)
        self.points, self.folds, self.v, self.tangent = [], [], None, None

    def begin_at(self, value, unknowns=None) -> bool:
        self.v, self.tangent = np.zeros(1), np.ones(1)
        return self.advance(value)

    def advance(self, value=None) -> bool:
        from types import SimpleNamespace

        value = self.points[-1].value + 0.5 if value is None else value
        self.points.append(SimpleNamespace(value=value))
        return True

    def target(self):
        return self.grid[-1]


def test_the_bar_shows_how_far_a_branch_has_got_between_two_values(monkeypatch):
    """The continuation's bar counts requested values; after it, the continued quantity at
    the branch's last point and the points so far, moving with every point."""
    from herringbone.analysis import continuation

    shown = []

    class Recording(bars.QuietBar):
        def set_postfix_str(self, postfix="", refresh=True):
            shown.append((self.n, postfix))

    monkeypatch.setattr(continuation, "progress_bar", lambda total, *_, **__: Recording(total))
    continuation.follow(CreepingBranch(), progress=True, doubling=False)
    assert shown[0] == (1, "w0_pinion 10 rad/s, 1 point")
    assert (1, "w0_pinion 17.5 rad/s, 16 points") in shown  # the count stands, the status moves
    assert shown[-1] == (2, "w0_pinion 30 rad/s, 41 points")


def test_a_bar_in_a_log_ends_with_the_branchs_status(monkeypatch):
    """In a log the status is redrawn at the bar's pace (no line per point): its last line
    ends with where the branch got."""
    from herringbone.analysis import continuation

    monkeypatch.delitem(sys.modules, "ipykernel", raising=False)
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    continuation.follow(CreepingBranch(), progress=True, doubling=False)
    shown = [line for line in sys.stderr.getvalue().split("\r") if line.strip()]
    assert len(shown) == 2 and shown[-1].rstrip().endswith("w0_pinion 30 rad/s, 41 points]")
