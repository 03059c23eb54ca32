"""A sweep on a LocalCluster refuses, in one message and before any worker starts, a main
script whose workers could not start (analysis/distributed_run.check_workers_can_start):
Dask's worker processes import the main script again as they start."""
import subprocess
import sys
import types
from pathlib import Path

import pytest

from herringbone.analysis import distributed_run

SWEEP = ('herringbone.sweep(herringbone.load_scene("reference"), speeds=[100.0, 200.0], '
         'params={"zeta_mesh": [0.01, 0.02]}, protocol=SHORT, workers=2, progress=False)')
HEADER = ("import herringbone\n"
          "from herringbone.analysis.sweep_point import Protocol\n"
          "SHORT = Protocol(settle_time=0.01, window_periods=2)\n")


def run_script(text: str, folder: Path, stdin: bool = False) -> subprocess.CompletedProcess:
    script = folder / "grid.py"
    script.write_text(text)
    argv = [sys.executable, "-"] if stdin else [sys.executable, str(script)]
    return subprocess.run(argv, input=text if stdin else None, capture_output=True, text=True,
                          cwd=folder, timeout=120)


def test_a_script_that_sweeps_from_its_top_level_is_told_to_guard_it(tmp_path):
    run = run_script(HEADER + f"table = {SWEEP}\n", tmp_path)
    assert run.returncode == 1
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("RuntimeError: a sweep on 2 worker processes: ")
    assert f"{tmp_path / 'grid.py'} starts it from its top level (line 4)" in last
    assert 'if __name__ == "__main__":' in last and "workers=0" in last
    assert "Nanny" not in run.stderr and "bootstrapping" not in run.stderr  # no worker started


def test_a_script_read_from_stdin_is_told_that_workers_cannot_import_it(tmp_path):
    run = run_script(HEADER + f"table = {SWEEP}\n", tmp_path, stdin=True)
    assert run.returncode == 1
    last = run.stderr.strip().splitlines()[-1]
    assert "the main script" in last and "<stdin> is no file" in last and "workers=0" in last
    assert "Nanny" not in run.stderr


def test_a_guarded_script_sweeps_on_its_workers(tmp_path):
    text = HEADER + ("\n\ndef main():\n"
                     f"    print({SWEEP}.K_v.round(3).tolist())\n\n\n"
                     "if __name__ == \"__main__\":\n    main()\n")
    run = run_script(text, tmp_path)
    assert run.returncode == 0, run.stderr
    k_v = eval(run.stdout.strip().splitlines()[-1])
    assert len(k_v) == 4 and all(1.0 < value < 2.0 for value in k_v)


GUARDS = ['if __name__ == "__main__":\n    x = 1\n    sweep()\n',
          "if '__main__' == __name__:\n    sweep()\n",
          'if __name__ == "__main__" and True:\n    sweep()\n']


@pytest.mark.parametrize("text", GUARDS)
def test_a_line_under_a_guard_is_guarded(text, tmp_path):
    script = tmp_path / "s.py"
    script.write_text("import os\n" + text)
    lines = len(script.read_text().splitlines())
    assert distributed_run.guarded(script, lines)
    assert not distributed_run.guarded(script, 1)  # the import above the guard


def test_an_unreadable_script_is_not_refused(tmp_path):
    (tmp_path / "bad.py").write_text("def (:\n")
    assert distributed_run.guarded(tmp_path / "bad.py", 1)
    assert distributed_run.guarded(tmp_path / "missing.py", 1)


def fake_main(name=None, origin=None, file=None) -> types.ModuleType:
    main = types.ModuleType("__main__")
    main.__spec__ = None if name is None else types.SimpleNamespace(name=name, origin=origin)
    if file is not None:
        main.__file__ = file
    return main


@pytest.mark.parametrize("main, script", [
    (fake_main(file="/a/run.py"), Path("/a/run.py")),            # python run.py
    (fake_main("tool", "/a/tool.py", "/a/tool.py"), Path("/a/tool.py")),  # python -m tool
    (fake_main("pkg.__main__", "/a/pkg/__main__.py"), None),      # python -m pkg: not rerun
    (fake_main(), None),                                          # python -c, a notebook
    (fake_main(file="/usr/bin/ipython"), None),                   # IPython
])
def test_the_main_script_is_the_one_spawn_runs_again(main, script, monkeypatch):
    monkeypatch.setitem(sys.modules, "__main__", main)
    assert distributed_run.main_script() == script


def test_the_interrupt_is_ignored_while_workers_start_and_handled_again_after():
    import signal

    before = signal.getsignal(signal.SIGINT)
    with distributed_run.interrupts_ignored():
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    assert signal.getsignal(signal.SIGINT) is before
    with pytest.raises(KeyError), distributed_run.interrupts_ignored():
        raise KeyError("a cluster that failed to start")
    assert signal.getsignal(signal.SIGINT) is before


def test_a_closing_worker_says_nothing_of_what_its_closing_does():
    """On the sweep's own workers, closing after an error or Ctrl-C: the tasks' cancellation
    (a warning) and a heartbeat that meets the scheduler already closed (an error with a page
    of traceback, seen once in CI after the command's one line) are the closing itself."""
    import logging

    from herringbone.analysis.distributed_run import quiet_cancellations

    names = ("distributed.worker.state_machine", "distributed.worker")
    before = [logging.getLogger(name).level for name in names]
    try:
        quiet_cancellations()
        assert not logging.getLogger("distributed.worker").isEnabledFor(logging.ERROR)
        assert not logging.getLogger("distributed.worker.state_machine").isEnabledFor(
            logging.WARNING)
    finally:
        for name, level in zip(names, before):
            logging.getLogger(name).setLevel(level)
