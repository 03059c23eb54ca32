"""How `walk.advance`'s records travel: a few flat buffers, taken apart in compiled code.

numba types and unboxes every array of a call's arguments at every call (some 0.1 µs each),
and the FMU calls `advance` once per communication step, where a step of an exact segment
costs a few µs. So the stepper's constants travel as two buffers (`pack_constants`: the
packed System, the mesh period and the settings), and a run as two more (`pack_run`: its
position and its scratch); the exponential method's tables as exponential.pack_tables' three,
and Radau IIA's factors as their own three arrays. In compiled code `unpack_constants` and
`unpack_run` hand back views of them, with no copy and no count of references
(compiling.counting); in Python `run_views` gives the same views as numpy arrays, so that the
run's position can be read and set where advance reads and writes it.

Layouts. The constants' floats are the packed System's floats (equations.pack_system), then
the intervals' lengths (rad), the point tables (intervals × POINT_FIELDS × the widest set's
points) and the settings; their ints the System's ints, then the intervals' point counts and
CONSTANTS_TRAILER entries that say where each part starts. A run's floats hold its parts in
RunPart's order; its ints open with where each part starts (RunPart.END: where the last
ends), then the width of the values' rows, the place (contact interval, mesh cycle) and the
counters.
"""
from __future__ import annotations

from enum import IntEnum

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array

from ...model.equations import POINT_FIELDS, PeriodTable, unpack_system


class RunPart(IntEnum):
    """The parts of a run's float buffer, in order."""

    CLOCK = 0  # [time, step size to try next], s
    STATE = 1  # [y, ẏ]
    LOADED = 2  # per point of the set (padded to the widest set): 1 loaded, 0 not
    FIRST_STEPS = 3  # per contact interval, the step size to start it with, s; 0: none
    OUTPUTS = 4  # equations.outputs at the run's position
    VECTORS = 5  # the workspace's rows of the state's length (walk.Vector)
    VALUES = 6  # the workspace's rows of event values (walk.Values)
    MEMORY = 7  # the loop's floats (walk.Memory)
    END = 8  # (where the last part ends)


# a run's ints after the parts' starts: the width of a row of values, the place, the counters
VALUES_WIDTH = RunPart.END + 1
PLACE = VALUES_WIDTH + 1
COUNTERS = PLACE + 2
# the constants' ints end with where the lengths, the tables and the settings start in the
# floats, where the settings end, the number of intervals, the widest set's points, and where
# the counts start in the ints
CONSTANTS_TRAILER = 7


def pack_constants(system_arrays: tuple[np.ndarray, np.ndarray], mesh: PeriodTable,
                   settings: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The stepper's constants as (floats, ints): the packed System (equations.pack_system's
    two arrays), the mesh period (lengths, counts, tables) and the settings
    (walk.pack_settings)."""
    system_floats, system_ints = system_arrays
    lengths, counts, tables = mesh
    parts = [system_floats, lengths, tables.ravel(), settings]
    starts = np.cumsum([0] + [len(part) for part in parts])
    trailer = [starts[1], starts[2], starts[3], starts[4], len(lengths), tables.shape[2],
               len(system_ints)]
    return (np.concatenate(parts).astype(np.float64),
            np.concatenate([system_ints, counts, trailer]).astype(np.int64))


def pack_run(clock, place, state, loaded, first_steps, outputs, vector_rows: int,
             value_rows: int, values_width: int, memory: int, counters: int
             ) -> tuple[np.ndarray, np.ndarray]:
    """A run as (floats, ints): its position (copied in), and its scratch zeroed: vector_rows
    rows of the state's length, value_rows rows of values_width values, `memory` floats and
    `counters` ints."""
    parts = [clock, state, loaded, first_steps, outputs,
             np.zeros(vector_rows * len(state)), np.zeros(value_rows * values_width),
             np.zeros(memory)]
    starts = np.cumsum([0] + [len(part) for part in parts])
    return (np.concatenate(parts).astype(np.float64),
            np.concatenate([starts, [values_width], place, np.zeros(counters)]).astype(np.int64))


def run_views(buffers: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, ...]:
    """pack_run's buffers taken apart as numpy views: (clock, place, state, loaded,
    first_steps, outputs, vectors, values, counters, memory), each as `unpack_run` gives it."""
    floats, ints = buffers
    part = [floats[ints[k]:ints[k + 1]] for k in range(RunPart.END)]
    return (part[RunPart.CLOCK], ints[PLACE:PLACE + 2], part[RunPart.STATE],
            part[RunPart.LOADED], part[RunPart.FIRST_STEPS], part[RunPart.OUTPUTS],
            part[RunPart.VECTORS].reshape(-1, len(part[RunPart.STATE])),
            part[RunPart.VALUES].reshape(-1, ints[VALUES_WIDTH]), ints[COUNTERS:],
            part[RunPart.MEMORY])


# --- in compiled code -----------------------------------------------------------------------

@intrinsic
def _c_ordered_view(typing_context, buffer, shape, strides):
    """A view of `buffer`'s data with this shape and these strides (bytes), typed C-contiguous:
    numba's own such view (reshape_unchecked, what its as_strided makes) is typed of any
    layout, and DOP853's stages read through views of any layout ran a quarter slower. Only
    for a C-ordered block of a contiguous buffer (matrix_view, cube_view)."""
    if not isinstance(buffer, types.Array):
        return None
    result = buffer.copy(ndim=len(shape), layout="C")

    def codegen(context, builder, signature, args):
        array = make_array(buffer)(context, builder, args[0])
        view = make_array(result)(context, builder)
        populate_array(view, data=array.data, shape=cgutils.unpack_tuple(builder, args[1]),
                       strides=cgutils.unpack_tuple(builder, args[2]),
                       itemsize=array.itemsize, meminfo=array.meminfo)
        return impl_ret_borrowed(context, builder, result, view._getvalue())

    return result(buffer, shape, strides), codegen


# Not a reshape: numba's checks the layout through a call of its runtime, and each kernel
# takes its buffers apart at every call; nor as_strided, a compiled function returning an
# array, which code compiled without reference counts (compiling.counting) may not call.

@njit(cache=True, error_model="numpy", inline="always")
def matrix_view(buffer, at, rows, columns):
    """The C-ordered rows × columns block of the flat `buffer` from entry `at`, as a view."""
    item = buffer.itemsize
    return _c_ordered_view(buffer[at:], (rows, columns), (columns * item, item))


@njit(cache=True, error_model="numpy", inline="always")
def cube_view(buffer, at, pages, rows, columns):
    """The C-ordered pages × rows × columns block of the flat `buffer` from entry `at`, as a
    view."""
    item = buffer.itemsize
    return _c_ordered_view(buffer[at:], (pages, rows, columns),
                           (rows * columns * item, columns * item, item))


@njit(cache=True, error_model="numpy", inline="always")
def unpack_constants(buffers):
    """pack_constants' inverse: (the System, the PeriodTable, the settings), views of the
    two buffers."""
    floats, ints = buffers
    trailer = ints.shape[0] - CONSTANTS_TRAILER
    at_lengths, at_tables, at_settings, end = (ints[trailer], ints[trailer + 1],
                                               ints[trailer + 2], ints[trailer + 3])
    intervals, widest, at_counts = ints[trailer + 4], ints[trailer + 5], ints[trailer + 6]
    mesh = PeriodTable(floats[at_lengths:at_tables], ints[at_counts:at_counts + intervals],
                       cube_view(floats, at_tables, intervals, POINT_FIELDS, widest))
    return unpack_system(floats, ints), mesh, floats[at_settings:end]


@njit(cache=True, error_model="numpy", inline="always")
def unpack_run(buffers):
    """pack_run's inverse, as run_views: views of the two buffers."""
    floats, ints = buffers
    size = ints[RunPart.STATE + 1] - ints[RunPart.STATE]
    width = ints[VALUES_WIDTH]
    vectors = matrix_view(floats, ints[RunPart.VECTORS],
                          (ints[RunPart.VECTORS + 1] - ints[RunPart.VECTORS]) // size, size)
    values = matrix_view(floats, ints[RunPart.VALUES],
                         (ints[RunPart.VALUES + 1] - ints[RunPart.VALUES]) // width, width)
    return (floats[ints[RunPart.CLOCK]:ints[RunPart.CLOCK + 1]], ints[PLACE:PLACE + 2],
            floats[ints[RunPart.STATE]:ints[RunPart.STATE + 1]],
            floats[ints[RunPart.LOADED]:ints[RunPart.LOADED + 1]],
            floats[ints[RunPart.FIRST_STEPS]:ints[RunPart.FIRST_STEPS + 1]],
            floats[ints[RunPart.OUTPUTS]:ints[RunPart.OUTPUTS + 1]], vectors, values,
            ints[COUNTERS:], floats[ints[RunPart.MEMORY]:ints[RunPart.MEMORY + 1]])
