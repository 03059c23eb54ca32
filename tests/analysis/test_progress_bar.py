"""The progress bar: on a terminal tqdm's pace, in a log a line every LOG_INTERVAL seconds."""
import io
import sys

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
