"""What the FMU says to its host before an FMI call returns (fmu/pythonfmu_logger.HostLine): the
integrator's first start speaks `logging` levels, the host hears FMI statuses."""
import logging

from pythonfmu.enums import Fmi2Status

from herringbone.fmu.pythonfmu_logger import HostLine
from herringbone.integrate import first_start


class LoggingSlave:
    """As much of a pythonfmu slave as HostLine reads: its instance name and its log."""

    instance_name = "gear"

    def __init__(self):
        self.logged = []

    def log(self, message, status):
        self.logged.append((status, message))


def test_a_warning_reaches_the_host_as_a_warning_and_the_rest_as_ok(capsys):
    """Outside fmi2Instantiate (no host logger to call at once) a message goes to stderr and
    into the slave's log, a WARNING as fmi2Warning and an INFO as fmi2OK."""
    slave = LoggingSlave()
    line = HostLine(slave)
    line.say("compiling the integrator", logging.INFO)
    line.say("cannot copy the compiled integrator", logging.WARNING)
    assert slave.logged == [(Fmi2Status.ok, "gear: compiling the integrator"),
                            (Fmi2Status.warning, "gear: cannot copy the compiled integrator")]
    assert "herringbone FMU gear: cannot copy" in capsys.readouterr().err


def test_a_carried_cache_that_cannot_be_copied_reaches_the_host_as_a_warning(tmp_path,
                                                                              monkeypatch):
    """first_start.prepare, where the compiled code the FMU carries cannot be copied into the
    user's cache (an OSError), says so once, and the host hears it as fmi2Warning, naming
    HERRINGBONE_CACHE_DIR, the way out."""
    def unwritable(carried):
        raise PermissionError(13, "Permission denied", str(carried))

    monkeypatch.setattr(first_start.cache, "seed_from", unwritable)
    monkeypatch.setattr(first_start, "announce_compiles", lambda say: None)
    (tmp_path / first_start.CARRIED_FOLDER).mkdir()
    slave = LoggingSlave()
    first_start.prepare(tmp_path, HostLine(slave).say)
    [(status, message)] = slave.logged
    assert status == Fmi2Status.warning and "HERRINGBONE_CACHE_DIR" in message
