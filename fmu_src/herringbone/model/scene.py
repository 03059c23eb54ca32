"""Scene files: a gear train, its experiment and its input torques, loaded and validated once.

A scene file is TOML with four tables, all optional:

    [parameters]   values by their FMU names; anything not given takes the reference value
    [components]   motor, load, bearings = true/false (default true)
    [experiment]   stop_time, output_interval
    [inputs]       M_motor = 500, M_load = 1800   (constants), or
                   table = [[time, M_motor, M_load], ...]   (each row held until the next)

Every problem is reported as one SceneError naming the file, the key and what is allowed; a
value handed over by Scene.with_parameters or Scene.with_inputs is named by that call, not the
file (the file did not say it).
"""
from __future__ import annotations

import bisect
import math
import os
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import cast

from ..shipped import is_scene_name, resolve_scene, scene_files
from ..suggest import did_you_mean
from .geometry import HALVES, GearGeometry, solid_cylinder_transverse_inertia
from .parameters import (
    COMPONENTS,
    FINITE,
    INPUTS,
    PARAMETERS,
    POSITIVE,
    check_value,
    is_flag,
    number_problem,
    parameters_of,
    short_repr,
)


class SceneError(ValueError):
    """A scene that cannot be simulated; the message names the culprit and what is allowed.

    Its fields say where the problem lies, for a caller that words it its own way (the FMU):
    `source` the file (or "<scene>"; None where there is no scene at all; for a value of a
    `call`, the file of the scene it changed), `table` the table of the scene file
    ("parameters", "components", "experiment", "inputs"; None for the file as a whole), `key`
    the parameter, component or key at fault (None if none), `problem` what is wrong, the key
    named in it ("z_pinion is 0; allowed: >= 1"), `call` the function that handed the value
    over ("with_parameters", "with_inputs", "load_scene"; None: it came from the file or dict,
    `source`). str() is the one-line message "SOURCE: [TABLE] PROBLEM" (without the parts that
    are None), or "CALL: PROBLEM" for a value of a call: its scene's file did not say it."""

    def __init__(self, problem: str, source: str | None = None, table: str | None = None,
                 key: str | None = None, call: str | None = None):
        self.problem, self.source, self.table, self.key = problem, source, table, key
        self.call = call
        prefix = "" if source is None else f"{source}: "
        where = f"{prefix}{'' if table is None else f'[{table}] '}" if call is None \
            else f"{call}: "
        super().__init__(f"{where}{problem}")

    def __reduce__(self):
        """Pickled with its fields (a sweep's workers send it back to the client)."""
        return type(self), (self.problem, self.source, self.table, self.key, self.call)


@dataclass(frozen=True)
class Experiment:
    """A scene's run: simulated time and the interval between output samples, seconds."""

    stop_time: float = 0.1
    output_interval: float = 1e-4


@dataclass(frozen=True)
class InputSchedule:
    """Input torques as a step function of time: row i holds from times[i] to times[i + 1]."""

    times: tuple[float, ...] = (0.0,)
    M_motor: tuple[float, ...] = (cast(float, INPUTS["M_motor"].default),)
    M_load: tuple[float, ...] = (cast(float, INPUTS["M_load"].default),)

    def at(self, time: float) -> tuple[float, float]:
        """(M_motor, M_load), N·m, held at `time` (s): the last row at or before it."""
        row = max(bisect.bisect_right(self.times, time) - 1, 0)
        return self.M_motor[row], self.M_load[row]

    def change_times(self) -> tuple[float, ...]:
        """The times (s) after 0 at which the torques change."""
        return self.times[1:]


@dataclass(frozen=True)
class Scene:
    """A validated gear train: its components, the parameters it sets (and all it carries,
    completed with reference values and derived inertias), its experiment and input torques,
    and the file it came from."""

    name: str
    components: dict[str, bool]
    given: dict[str, float | int | bool]  # the parameters the scene sets itself
    experiment: Experiment = field(default_factory=Experiment)
    inputs: InputSchedule = field(default_factory=InputSchedule)
    source: str = "<scene>"
    # every parameter the train carries: the given ones, reference values, derived inertias
    parameters: dict[str, float | int | bool] = field(init=False)

    def __post_init__(self):
        object.__setattr__(self, "parameters",
                           _complete_parameters(self.given, self.components, self.source))

    def has(self, component: str) -> bool:
        """Whether the train has a component ("motor", "load" or "bearings")."""
        return self.components[component]

    def with_parameters(self, **changes) -> Scene:
        """A copy with some parameters changed, validated like a scene file.

        Examples
        --------
        >>> import herringbone
        >>> staggered = herringbone.load_scene("reference").with_parameters(stagger=0.5)
        >>> staggered.parameters["stagger"], staggered.parameters["w0_pinion"]
        (0.5, 157.08)
        >>> herringbone.load_scene("reference").with_parameters(zeta_mesh=-1.0)
        Traceback (most recent call last):
        herringbone.model.scene.SceneError: with_parameters: zeta_mesh is -1.0; allowed: [0, 10]
        """
        # checked here first, so that a bad value is named by this call, not the scene's file
        _check_parameters(changes, self.components, self.source, call="with_parameters")
        try:
            return replace(self, given={**self.given, **changes})
        except SceneError as error:  # parameters that do not go together (_check_edge_ramp)
            raise SceneError(error.problem, self.source, error.table, error.key,
                             "with_parameters") from None

    def with_inputs(self, M_motor=None, M_load=None, table=None, **unknown) -> Scene:
        """A copy with other input torques: constants (N·m; one left out keeps the scene's
        first), or a `table` of rows [time (s), M_motor, M_load (N·m)], each row's torques held
        from its time on, not both; validated like a scene file's [inputs], a keyword it does
        not know refused by name as a key of that table is (SceneError).

        Examples
        --------
        >>> import herringbone
        >>> stepped = herringbone.load_scene("reference").with_inputs(
        ...     table=[[0.0, 500.0, 1800.0], [0.01, 1000.0, 3600.0]])
        >>> stepped.inputs.at(0.005), stepped.inputs.at(0.02)  # (M_motor, M_load), N·m
        ((500.0, 1800.0), (1000.0, 3600.0))
        """
        given = {"M_motor": M_motor, "M_load": M_load, "table": table, **unknown}
        data = {key: value for key, value in given.items() if value is not None}
        if data.keys() <= {"M_motor", "M_load"}:
            data = {"M_motor": self.inputs.M_motor[0], "M_load": self.inputs.M_load[0], **data}
        return replace(self, inputs=_inputs(data, self.source, call="with_inputs"))


def toml_value(value) -> str:
    """A value as a scene file writes it, to every digit: true (not Python's True), 10,
    0.0004, 1e+16, inf, nan, a string quoted."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    return str(value) if isinstance(value, int) else repr(float(value))


def scene_file_text(scene: Scene, header: str = "") -> str:
    """`scene` as a scene file, each number to every digit (load_scene of it gives the same
    scene): its components, the parameters it sets, its experiment and torques, under
    `header` (a comment line, without its #; none where empty)."""
    lines = [f"# {header}", ""] if header else []
    lines += ["[components]",
              *(f"{name} = {toml_value(value)}" for name, value in scene.components.items()),
              "", "[parameters]",
              *(f"{name} = {toml_value(value)}" for name, value in scene.given.items()),
              "", "[experiment]", f"stop_time = {toml_value(scene.experiment.stop_time)}",
              f"output_interval = {toml_value(scene.experiment.output_interval)}", "",
              "[inputs]"]
    inputs = scene.inputs
    if len(inputs.times) == 1:
        lines += [f"M_motor = {toml_value(inputs.M_motor[0])}",
                  f"M_load = {toml_value(inputs.M_load[0])}"]
    else:
        rows = zip(inputs.times, inputs.M_motor, inputs.M_load)
        lines.append("table = [" + ", ".join(f"[{', '.join(map(toml_value, row))}]"
                                             for row in rows) + "]")
    return "\n".join(lines) + "\n"


def load_scene(path) -> Scene:
    """Read and validate a scene file (see the module docstring for its format).

    Parameters
    ----------
    path : str or pathlib.Path
        A TOML scene file, or the bare name of a shipped scene ("reference"; a file of that
        name wins; `herringbone scenes` lists them).

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        One line naming the file, the key and what is allowed (and the closest shipped name
        or parameter for a misspelt one); for a `path` that is no path (None, a number, ''),
        naming the argument.

    Examples
    --------
    >>> import herringbone
    >>> scene = herringbone.load_scene("reference")
    >>> scene.parameters["w0_pinion"], scene.inputs.M_motor  # rad/s, N·m
    (157.08, (500.0,))
    """
    given, path = path, resolve_scene(_scene_path(path))
    if path.is_dir():
        raise SceneError("a folder, not a scene file; allowed: a scene file (TOML) or the name "
                         "of a shipped scene (`herringbone scenes`)", str(path))
    if not path.is_file():
        names = (f"{did_you_mean(str(given), scene_files())}; shipped scenes: "
                 f"{', '.join(sorted(scene_files()))} (`herringbone scenes`)"
                 if is_scene_name(given) else "" if path.is_absolute()
                 else f" in {os.getcwd()}")
        raise SceneError(f"no such scene file{names}", str(path))
    text = ""
    try:
        text = path.read_text(encoding="utf-8")
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise SceneError(f"not a valid TOML file: {error}{_toml_line(error, text)}",
                         str(path)) from None
    return scene_from_dict(data, name=path.stem, source=str(path))


def _toml_line(error, text: str) -> str:
    """The line a TOML error is at, as the file has it (": `z_pinion = 12`"), where its
    message gives one: tomllib names the line, not the key ("Cannot overwrite a value (at
    line 3, column 14)" of a key given twice); '' where it gives none."""
    found = re.search(r"at line (\d+)", str(error))
    lines = text.splitlines()
    if found is None or not 1 <= int(found.group(1)) <= len(lines):
        return ""
    line = lines[int(found.group(1)) - 1].strip()
    repeated = " (a key given twice?)" if "overwrite" in str(error) else ""
    return f": `{line}`{repeated}" if line else ""


SCENE_PATH_ALLOWED = ("a scene file (TOML) as a str or pathlib.Path, or the name of a shipped "
                      "scene (`herringbone scenes`)")


def _scene_path(path):
    """`path` of load_scene if it can name a file; else SceneError naming the argument (an
    empty str would be read as the current folder)."""
    try:
        text = os.fspath(path)
    except TypeError:
        text = None
    if not isinstance(text, str):
        shown = repr(path)
        shown = f"{shown} ({type(path).__name__})" if len(shown) <= 60 else \
            f"a {type(path).__name__}"
        raise SceneError(f"path is {shown}; allowed: {SCENE_PATH_ALLOWED}", key="path",
                         call="load_scene")
    if not text:
        raise SceneError(f"path is {path!r} (empty); allowed: {SCENE_PATH_ALLOWED}", key="path",
                         call="load_scene")
    return path


def scene_from_dict(data: dict, name: str = "scene", source: str = "<scene>") -> Scene:
    """Validate a scene given as the tables of a scene file.

    Parameters
    ----------
    data : dict
        {"parameters": {...}, "components": {...}, "experiment": {...}, "inputs": {...}},
        any of them left out (their defaults: docs/model.md), SI units.
    name : str
        The scene's name.
    source : str
        Where it came from, for messages.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        One line naming the key and what is allowed (the argument, for `data` that is no
        dict).

    Examples
    --------
    >>> import herringbone
    >>> slower = herringbone.scene_from_dict(
    ...     {"parameters": {"w0_pinion": 100.0}, "inputs": {"M_motor": 400.0, "M_load": 1440.0}})
    >>> slower.parameters["w0_pinion"], slower.parameters["zeta_mesh"]  # the rest: reference's
    (100.0, 0.05)
    >>> herringbone.scene_from_dict({"parameters": {"zeta_mesh": -1.0}})
    Traceback (most recent call last):
    herringbone.model.scene.SceneError: <scene>: [parameters] zeta_mesh is -1.0; allowed: [0, 10]
    """
    if not isinstance(data, Mapping):
        raise SceneError(f"data is {data!r} ({type(data).__name__}); allowed: a dict of the "
                         f"scene file's tables, {{\"parameters\": {{...}}, "
                         "\"components\": {...}, \"experiment\": {...}, \"inputs\": {...}}, "
                         "any of them left out", key="data", call="scene_from_dict")
    unknown = set(data) - set(TABLES)
    if unknown:
        key = sorted(unknown, key=str)[0]
        raise SceneError(_unknown_table(key, data[key]), source, key=key)
    components = _components(_table(data, "components", source), source)
    return Scene(name=name, components=components,
                 given=dict(_table(data, "parameters", source)),
                 experiment=_experiment(_table(data, "experiment", source), source),
                 inputs=_inputs(_table(data, "inputs", source), source), source=source)


def _table(data, key, source):
    table = data.get(key, {})
    if not isinstance(table, dict):
        raise SceneError(f"'{key}' must be a table [{key}], got {table!r}", source, key=key)
    return table


# a scene file's tables, and the keys each holds
TABLES = {"parameters": tuple(PARAMETERS), "components": tuple(COMPONENTS),
          "experiment": ("stop_time", "output_interval"), "inputs": (*INPUTS, "table")}


def _unknown_table(key, value) -> str:
    """What is wrong with a top-level `key` of a scene that is not one of its TABLES: a key
    of a table written outside it ("stop_time = 0.1" above every table), or a misspelt
    table."""
    allowed = ", ".join(f"[{table}]" for table in TABLES)
    if not isinstance(value, Mapping):
        home = next((table for table, keys in TABLES.items() if key in keys), None)
        where = (f"; allowed: under [{home}]" if home is not None
                 else f"; allowed: keys under a table, {allowed}")
        return f"{key} stands outside any table{where}"
    return f"unknown table [{key}]{did_you_mean(key, TABLES)}; allowed: {allowed}"


def _components(table, source):
    components = {}
    for key, value in table.items():
        if key not in COMPONENTS:
            raise SceneError(f"unknown component '{key}'; allowed: {', '.join(COMPONENTS)}"
                             f"{did_you_mean(key, COMPONENTS)}",
                             source, "components", key)
        if not is_flag(value):
            raise SceneError(f"{key} must be true or false, got {short_repr(value)}", source,
                             "components", key)
        components[key] = bool(value)
    return {c: components.get(c, True) for c in COMPONENTS}


def _check_parameters(given, components, source, call=None):
    """SceneError for the first of the `given` parameters that is unknown, of a component the
    train leaves out, or out of its range; `call` names where they came from (None: the
    file or dict `source`)."""
    carried = parameters_of(components)
    for key, value in given.items():
        if key not in PARAMETERS:
            hint = (" (inputs belong in [inputs])" if key in INPUTS
                    else f": {key} is a component; allowed: a scene's [components] sets it"
                    if key in COMPONENTS
                    else f" ([parameters.{key}] is a table; allowed: parameters as keys under "
                         "[parameters], no tables in it)" if isinstance(value, dict)
                    else did_you_mean(key, PARAMETERS))
            raise SceneError(f"unknown parameter '{key}'{hint}", source, "parameters", key, call)
        if key not in carried:
            raise SceneError(f"{key} belongs to the component '{PARAMETERS[key].component}', "
                             "which this scene leaves out "
                             f"([components] {PARAMETERS[key].component} = false)",
                             source, "parameters", key, call)
        problem = check_value(PARAMETERS[key], value)
        if problem:
            raise SceneError(f"{key} {problem}", source, "parameters", key, call)


def _complete_parameters(given, components, source):
    _check_parameters(given, components, source)
    carried = parameters_of(components)
    values = {name: given.get(name, p.default) for name, p in carried.items()}
    for name, p in carried.items():
        if p.kind is int:
            values[name] = int(values[name])
        elif p.kind is float and values[name] is not None:
            values[name] = float(values[name])
        elif p.kind is bool:  # numpy's np.bool_ too
            values[name] = bool(values[name])
    _check_axial_overlap(values, source)
    _check_edge_ramp(values, source)
    derived = [f"J_{gear}" for gear in ("pinion", "wheel")
               if components["bearings"] and values[f"J_{gear}"] is None]
    for name in derived:
        values[name] = _derived_inertia(values, name[2:], source)
    _check_time_scales(values, components, source, derived)
    return values


def _derived_inertia(values, gear, source):
    """J of a gear its scene leaves out: a solid cylinder of its pitch radius and body
    (geometry.py), SceneError where that falls outside J's range (a 1e7 kg wheel of 1 m module
    and 1000 teeth would be 7e11 kg.m2), naming the values it follows from."""
    inertia = solid_cylinder_transverse_inertia(values, gear)
    allowed = PARAMETERS[f"J_{gear}"].allowed
    if not allowed.contains(inertia):
        raise SceneError(
            f"J_{gear} (not given: the solid cylinder m(3R^2+L^2)/12 of m_{gear} "
            f"{values[f'm_{gear}']:g} kg, its pitch radius and the body's length) is "
            f"{inertia:.3g} kg.m2; allowed: {allowed.describe()} kg.m2 (give J_{gear})",
            source, "parameters", f"J_{gear}")
    return inertia


# The fastest an element of the train (a shaft, a bearing, the mesh) may ring, rad/s, and the
# fastest it may damp a motion, 1/s: the square root of its stiffness, and its damping, times
# Σ g²/m over the bodies it joins (g: its lever on each; element_rates). No lumped mode of a
# gear train is faster (sound crosses a tooth of 10 µm module in 5 ns), and a run steps at
# about the fastest: bearings of 1e13 N/m on a pinion of 1e-7 kg (1e10 rad/s) take 41 s for
# 2 ms, I_pinion = 1e-18 fails at the first step (the step below the time's resolution), and
# from 1e9 rad/s `info` loses a natural mode to rounding. The reference's fastest rings at
# 1.1e5 rad/s, the fastest of 3000 random scenes the tests draw at 2.6e6 (and damps at 1.5e6
# 1/s).
FASTEST_RING = 1e8
FASTEST_DAMPING = 1e9


def element_rates(values, components) -> list[tuple[str, str, str, float, float, float, dict]]:
    """Each elastic element of the train as (what it is, its stiffness parameter, its damping
    parameter, its stiffness, its natural frequency sqrt(c·Σ g²/m) in rad/s, its damping rate
    h·Σ g²/m in 1/s, {body parameter: its share g²/m}): g is the element's lever on the body
    (1, a pitch radius, a bearing's or the face's distance from the gear's centre). The mesh
    carries the points of every stream at once (ε_β and the edge ramps rounded up) and is
    damped at 2·zeta_mesh times its frequency (docs/model.md section 3)."""
    geometry = GearGeometry.from_parameters(values)
    elements = []  # (what, its stiffness and damping parameters, its stiffness, shares)
    if components["motor"]:
        elements.append(("the input shaft", "C_shaft_in", "h_shaft_in", values["C_shaft_in"],
                         {"I_motor": 1.0 / values["I_motor"],
                          "I_pinion": 1.0 / values["I_pinion"]}))
    if components["load"]:
        elements.append(("the output shaft", "C_shaft_out", "h_shaft_out",
                         values["C_shaft_out"], {"I_wheel": 1.0 / values["I_wheel"],
                                                 "I_load": 1.0 / values["I_load"]}))
    lever = values["groove"] / 2.0 + max(values["b_left"], values["b_right"])
    mesh = {"I_pinion": geometry.radius_pinion ** 2 / values["I_pinion"],
            "I_wheel": geometry.radius_wheel ** 2 / values["I_wheel"]}
    if components["bearings"]:
        for gear in ("pinion", "wheel"):
            mesh.update({f"m_{gear}": 1.0 / values[f"m_{gear}"],
                         f"J_{gear}": lever ** 2 / values[f"J_{gear}"]})
            for side in ("left", "right"):
                elements.append((f"the {side} {gear} bearing", f"c_brg_{gear}_{side}",
                                 f"h_brg_{gear}_{side}", values[f"c_brg_{gear}_{side}"],
                                 {f"m_{gear}": 1.0 / values[f"m_{gear}"],
                                  f"J_{gear}": geometry.bearing_position(side) ** 2
                                  / values[f"J_{gear}"]}))
    ramp = 2.0 * values["edge_ramp"] / geometry.axial_pitch
    points = 2 * sum(math.ceil(geometry.axial_overlap(half) + ramp) for half in HALVES)
    elements.append(("the mesh", "c_point", "zeta_mesh", values["c_point"] * points, mesh))
    rates = []
    for what, name, damping, stiffness, shares in elements:
        ring = math.sqrt(stiffness * sum(shares.values()))
        rate = 2.0 * values["zeta_mesh"] * ring if damping == "zeta_mesh" \
            else values[damping] * sum(shares.values())
        rates.append((what, name, damping, stiffness, ring, rate, shares))
    return rates


def _check_time_scales(values, components, source, derived=()):
    """SceneError where an element rings faster than FASTEST_RING or damps faster than
    FASTEST_DAMPING (element_rates), naming first (the key) the light body that makes it ring,
    or the damping that damps it, then the element and its stiffness or its body; `derived`:
    the inertias the scene did not give (said so, with the mass they follow)."""
    for what, name, damping, stiffness, ring, rate, shares in element_rates(values,
                                                                            components):
        body = max(shares, key=lambda key: shares[key])
        weight = f"{values[body]:.3g} {PARAMETERS[body].unit}"
        if body in derived:
            mass = f"m_{body[2:]}"
            weight += f" (not given: the solid cylinder of {mass} {values[mass]:g} kg)"
        if ring > FASTEST_RING:
            by = (f"{name} {values[name]:g} {PARAMETERS[name].unit}" if name != "c_point" else
                  f"{round(stiffness / values[name])} points of c_point {values[name]:g} N/m")
            raise SceneError(
                f"{body} is {weight}, on which {what} rings at {ring:.3g} rad/s ({by}); "
                f"allowed: up to {FASTEST_RING:g} rad/s, sqrt(stiffness/mass) of each shaft, "
                "bearing and the mesh (no gear train has a faster mode, and a run steps at it)",
                source, "parameters", body)
        if rate > FASTEST_DAMPING:
            unit = PARAMETERS[damping].unit
            ringing = f" (ringing at {ring:.3g} rad/s)" if damping == "zeta_mesh" else ""
            raise SceneError(
                f"{damping} is {values[damping]:g}{'' if unit == '1' else ' ' + unit}, which "
                f"damps {what}{ringing} at {rate:.3g} 1/s on {body} {weight}; allowed: up to "
                f"{FASTEST_DAMPING:g} 1/s, damping/mass of each shaft, bearing and the mesh (a "
                "run steps at it)", source, "parameters", damping)


# The most axial pitches a helix half may span (ε_β = b/p_x): each holds a contact point of each
# of the half's two lines of engagement, and every point costs every step: 200 (1600 points on
# the mesh) run the reference's 2 ms in 0.3 s as 8 do, where a 35 mm face of 0.1 µm module
# (43 000) takes `info` 5.5 s. No gear is that wide: a face of 200 pitches is 980 modules at a
# helix of 40°.
MOST_AXIAL_PITCHES = 200


def _check_axial_overlap(values, source):
    """SceneError where a helix half spans more than MOST_AXIAL_PITCHES axial pitches
    p_x = π·m_n/sin β: naming the face, with the module and helix that make its pitch."""
    geometry = GearGeometry.from_parameters(values)
    for half in HALVES:
        pitches = geometry.axial_overlap(half)
        if pitches > MOST_AXIAL_PITCHES:
            key = f"b_{half}"
            most = MOST_AXIAL_PITCHES * geometry.axial_pitch
            raise SceneError(
                f"{key} is {values[key]!r} m, {pitches:.3g} axial pitches p_x = π·m_n/sin(beta) "
                f"= {geometry.axial_pitch:.3g} m (m_n {values['m_n']:g} m, beta "
                f"{values['beta']:g} rad); allowed: at most {MOST_AXIAL_PITCHES} pitches a "
                f"face, {key} <= {most:.3g} m with this m_n and beta (each pitch holds two "
                "contact points, and each point costs every step)", source, "parameters", key)


def _check_edge_ramp(values, source):
    """SceneError where the contact ellipse's half-length passes half the narrower face: no
    point would ever carry its full stiffness (a ramp of 1 given for 1 mm is 30 face widths)."""
    ramp, narrower = values["edge_ramp"], min(values["b_left"], values["b_right"])
    if ramp > 0.5 * narrower:
        raise SceneError(f"edge_ramp is {ramp!r} m, over half the narrower face width "
                         f"({narrower:g} m); allowed: <= {0.5 * narrower:g} m, the contact "
                         "ellipse's half-length in metres (1 mm is 0.001)",
                         source, "parameters", "edge_ramp")


def _experiment(table, source):
    values = {}
    for key, value in table.items():
        if key not in TABLES["experiment"]:
            hint = " (parameters belong in [parameters])" if key in PARAMETERS else ""
            raise SceneError(f"unknown key '{key}'{hint}; allowed: "
                             f"{', '.join(TABLES['experiment'])}"
                             f"{'' if hint else did_you_mean(key, TABLES['experiment'])}",
                             source, "experiment", key)
        problem = number_problem(value, POSITIVE, "s")
        if problem is not None:
            raise SceneError(f"{key} {problem}", source, "experiment", key)
        values[key] = float(value)
    if "output_interval" not in values and "stop_time" in values:
        # its default, 1e-4 s, would exceed a shorter run: one sample at its end then
        values["output_interval"] = min(Experiment.output_interval, values["stop_time"])
    experiment = Experiment(**values)
    if experiment.output_interval > experiment.stop_time:
        raise SceneError(f"output_interval {experiment.output_interval:g} s exceeds stop_time "
                         f"{experiment.stop_time:g} s; allowed: output_interval <= stop_time",
                         source, "experiment", "output_interval")
    return experiment


def _inputs(table, source, call=None):
    """The InputSchedule of an [inputs] table (constants or a table of rows); SceneError
    naming the key, and `call` where the values came from (None: the file or dict `source`)."""
    def error(problem, key):
        return SceneError(problem, source, "inputs", key, call)

    for key in table:
        if key not in INPUTS and key != "table":
            where = " (parameters belong in [parameters])" if key in PARAMETERS else ""
            raise error(f"unknown key '{key}'{where}; allowed: M_motor, M_load, table"
                        f"{'' if where else did_you_mean(key, [*INPUTS, 'table'])}", key)
    if "table" in table:
        if set(table) != {"table"}:
            raise error("give either constants (M_motor, M_load) or a table, not both", "table")
        rows = table["table"]
        if not isinstance(rows, list) or not rows:
            raise error("table must be a list of rows [time, M_motor, M_load]", "table")
        for i, row in enumerate(rows):
            if not isinstance(row, list) or len(row) != 3 or not all(
                    isinstance(v, (int, float))
                    and number_problem(v, FINITE) is None for v in row):
                shown = (f"[{', '.join(short_repr(v) for v in row)}]"
                         if isinstance(row, list) else repr(row))
                raise error(f"table row {i} is {shown}; allowed: three finite numbers "
                            "[time, M_motor, M_load]", "table")
        times = [float(row[0]) for row in rows]
        if times[0] != 0.0:
            raise error(f"table row 0 is at time {times[0]:g} s; allowed: a table that "
                        "starts at time 0 s", "table")
        for row, (before, time) in enumerate(zip(times, times[1:]), start=1):
            if time <= before:
                raise error(f"table row {row} is at time {time:g} s, not after row {row - 1}'s "
                            f"{before:g} s; allowed: times that increase strictly", "table")
        return InputSchedule(tuple(times), tuple(float(r[1]) for r in rows),
                             tuple(float(r[2]) for r in rows))
    values = {}
    for key, value in table.items():
        problem = check_value(INPUTS[key], value)
        if problem:
            raise error(f"{key} {problem}", key)
        values[key] = float(value)
    return InputSchedule((0.0,), (values.get("M_motor", INPUTS["M_motor"].default),),
                         (values.get("M_load", INPUTS["M_load"].default),))
