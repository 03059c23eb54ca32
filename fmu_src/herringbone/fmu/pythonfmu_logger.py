"""What pythonfmu 0.7 keeps in the logger object whose address it hands every slave (the
`logger` keyword of the slave's constructor), read with ctypes. pythonfmu tells a slave neither
whether the host enabled logging nor how to reach the host's logger before the FMI call returns
(it queues a slave's messages until then), and the gear FMU needs both: to say a problem on
stderr only where the host would not show it, and to announce a compile before it starts
(HostLine: the integrator's first start says it through one, integrate/first_start.py).

pythonfmu 0.7's C++ Fmi2Logger (its src/pythonfmu/fmi2.cpp and Logger.hpp): a vtable pointer,
the debug-logging flag at byte FLAG, the instance name (a std::string: data pointer, then size)
at NAME, the categories of fmi2SetDebugLogging (a std::vector of std::string: its first and
past-the-end pointers) at CATEGORIES, the host's fmi2CallbackFunctions pointer at FUNCTIONS.
A message reaches the host where the flag is set and the categories are none or hold the
message's own. It is read only under pythonfmu
0.7, and only after the name found there is the instance's own, the check that the layout is
the one described here; anything else answers None ("not known").

Nothing here imports pythonfmu: the FMI 3.0 FMU runs the same core (fmu/core.py builds a
HostLine for it too, with no logger) and carries pythonfmu3 alone, so a host need not have
pythonfmu for it. A logger can be pythonfmu's only where pythonfmu runs the slave, and then it
is imported already (`_running_pythonfmu`).
"""
from __future__ import annotations

import ctypes
import logging
import sys
import weakref
from collections.abc import Callable
from enum import IntEnum
from types import FrameType, ModuleType

FLAG, NAME, CATEGORIES, FUNCTIONS = 8, 16, 48, 72
STRING_SIZE = 32  # libstdc++'s std::string: data pointer, size, a 16-byte buffer
# fmi2CallbackLogger(environment, instance name, status, category, message)
_CALLBACK = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int,
                             ctypes.c_char_p, ctypes.c_char_p)


class Status(IntEnum):
    """The statuses HostLine says messages at: FMI 2.0's and FMI 3.0's numbers (fmi2Status,
    fmi3Status), and the names pythonfmu's and pythonfmu3's `log` make a category of
    (logStatusOk, logStatusWarning); either slave's log takes them."""
    ok = 0
    warning = 1


def _pointer(address: int, offset: int) -> int | None:
    return ctypes.c_void_p.from_address(address + offset).value


def _running_pythonfmu() -> ModuleType | None:
    """pythonfmu where this process imported it (it runs an FMI 2.0 slave), else None; never
    imports it (a host of the FMI 3.0 FMU may not have it)."""
    return sys.modules.get("pythonfmu")


def _is_instance(address: int | None, name: bytes) -> bool:
    """Whether `address` is pythonfmu 0.7's logger of the instance called `name`."""
    pythonfmu = _running_pythonfmu()
    if not address or pythonfmu is None or not pythonfmu.__version__.startswith("0.7."):
        return False
    size = ctypes.c_size_t.from_address(address + NAME + 8).value
    data = _pointer(address, NAME)
    if not data or size != len(name):
        return False
    return ctypes.string_at(data, size) == name


def logging_on(address: int | None, instance_name: str) -> bool | None:
    """Whether pythonfmu passes the instance's log messages to the host (loggingOn of
    fmi2Instantiate, or fmi2SetDebugLogging); None where that cannot be known."""
    if not _is_instance(address, instance_name.encode()):
        return None
    assert address is not None
    return bool(ctypes.c_bool.from_address(address + FLAG).value)


def hears(address: int | None, instance_name: str, category: str) -> bool | None:
    """Whether pythonfmu passes the instance's log messages of `category` to the host: logging
    is on and fmi2SetDebugLogging enabled no categories, or this one among them; None where
    that cannot be known."""
    on = logging_on(address, instance_name)
    if not on:
        return on
    assert address is not None
    first, end = _pointer(address, CATEGORIES), _pointer(address, CATEGORIES + 8)
    if not first or not end or first == end:
        return True
    wanted = category.encode()
    for string in range(first, end, STRING_SIZE):
        size, data = ctypes.c_size_t.from_address(string + 8).value, _pointer(string, 0)
        if data and size == len(wanted) and ctypes.string_at(data, size) == wanted:
            return True
    return False


def host_logger(address: int | None, instance_name: str) -> Callable[[int, bytes], None] | None:
    """A call `(status, message)` straight into the host's fmi2CallbackLogger, for the instance
    called `instance_name`; None where the host turned logging off or the logger is unknown.
    Valid while the host's callbacks live: call it only inside the instance's FMI calls."""
    name = instance_name.encode()
    if not logging_on(address, instance_name):
        return None
    assert address is not None
    functions = _pointer(address, FUNCTIONS)  # fmi2CallbackFunctions: logger 1st, environment 5th
    logger = _pointer(functions, 0) if functions else None
    if not logger or not functions:
        return None
    environment = _pointer(functions, 4 * ctypes.sizeof(ctypes.c_void_p))
    callback = _CALLBACK(logger)
    return lambda status, text: callback(environment, name, status, None, text)


class HostLine:
    """A direct line to the host's logger, for messages that cannot wait for the FMI call to
    return. `say(message, level)` (a `logging` level: WARNING and above reach the host as a
    warning, the rest as OK) calls the host's fmi2CallbackLogger at once where it can,
    else writes to stderr and queues the message with the slave's log as well.

    pythonfmu queues a slave's log messages and hands them over only when the FMI call returns
    (those of fmi2Instantiate at the next call), and a compile announced that way would be read
    after it is done. The host's logger is found through pythonfmu 0.7's own logger object
    (host_logger), and called only while the instance's __init__ runs (inside
    fmi2Instantiate, when the host's callbacks are certainly alive; compiles happen there)."""

    def __init__(self, slave, logger_address=None):
        self._slave = weakref.ref(slave)
        self._init = type(slave).__init__.__code__
        self._name = str(slave.instance_name).encode()
        self._call = host_logger(logger_address, str(slave.instance_name))

    def say(self, message: str, level: int = logging.INFO) -> None:
        """Show `message` to the host: through its logger callback while it instantiates the
        FMU, else on stderr (and in the slave's log, where there is a slave)."""
        status = Status.warning if level >= logging.WARNING else Status.ok
        text = f"{self._name.decode()}: {message}"
        if self._call is not None and self._instantiating():
            # hosts format the message printf-style
            self._call(status.value, text.replace("%", "%%").encode())
            return
        print(f"herringbone FMU {text}", file=sys.stderr, flush=True)
        slave = self._slave()
        if slave is not None:
            slave.log(text.replace("%", "%%"), status)

    def _instantiating(self) -> bool:
        frame: FrameType | None = sys._getframe(1)
        slave = self._slave()
        while frame is not None:
            if frame.f_code is self._init and frame.f_locals.get("self") is slave:
                return True
            frame = frame.f_back
        return False
