"""The parameters of the gear train: one table, read by the scene loader, the model and the FMU.

Every parameter is named as in docs/model.md (sections 2-6, 11), with its reference value, unit,
meaning, allowed range and the component that needs it. A scene that leaves a component out
carries none of that component's parameters.
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

COMPONENTS = ("motor", "load", "bearings")
# rpm per rad/s: the one conversion of a speed to revolutions per minute
RPM_PER_RAD_S = 30.0 / math.pi


@dataclass(frozen=True)
class Range:
    """An interval of allowed values; bounds of None are unbounded."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False

    def contains(self, value: float) -> bool:
        """Whether `value` is finite and inside the interval (open bounds excluded)."""
        if not math.isfinite(value):
            return False
        if self.low is not None and (value < self.low or (self.low_open and value == self.low)):
            return False
        if self.high is not None and (value > self.high or (self.high_open and value == self.high)):
            return False
        return True

    def describe(self) -> str:
        """The interval in words, as messages show it: "> 0", "[1e-12, 0.01]", "(0, 1.5708)"."""
        if self.low is None and self.high is None:
            return "any finite number"
        if self.high is None:
            return f"{'>' if self.low_open else '>='} {self.low:g}"
        if self.low is None:
            return f"{'<' if self.high_open else '<='} {self.high:g}"
        left = "(" if self.low_open else "["
        right = ")" if self.high_open else "]"
        return f"{left}{self.low:g}, {self.high:g}{right}"


POSITIVE = Range(0.0, None, low_open=True)
NON_NEGATIVE = Range(0.0, None)
FRACTION = Range(0.0, 1.0, high_open=True)
FINITE = Range()
# a tooth count: a ring gear of a thousand teeth is beyond any gearbox this model describes,
# and 1e20 teeth were taken and failed at the first step ("step size fell below the time's
# resolution") with pitch radii of 2e17 m
TOOTH_COUNT = Range(1, 1000)
HELIX_ANGLE = Range(0.0, math.pi / 2, low_open=True, high_open=True)
# |w0_pinion| (rad/s): 1e5 is 955 000 rpm, a rim speed of 2 km/s on the reference pinion, past
# any gear; 1e12 rad/s was taken and ran 1.6e8 mesh periods in 1e-4 s, the run looking hung
PINION_SPEED = Range(-1e5, 1e5)


@dataclass(frozen=True)
class Parameter:
    """One parameter (or input) of the train: its name, default (SI units), unit, meaning,
    type, allowed range and the component that carries it."""

    name: str
    default: float | int | bool | str | None  # None: derived from others (geometry.py)
    unit: str
    description: str
    kind: type = float
    allowed: Range = POSITIVE
    component: str | None = None  # None: every scene has it


def _p(name, default, unit, description, kind=float, allowed=POSITIVE, component=None):
    return Parameter(name, default, unit, description, kind, allowed, component)


PARAMETERS: dict[str, Parameter] = {p.name: p for p in [
    # geometry (docs/model.md section 2)
    _p("z_pinion", 10, "1", "number of pinion teeth", int, TOOTH_COUNT),
    _p("z_wheel", 36, "1", "number of wheel teeth", int, TOOTH_COUNT),
    _p("m_n", 0.004, "m", "normal module"),
    _p("beta", 0.398982, "rad", "helix angle on the pitch cylinder", allowed=HELIX_ANGLE),
    _p("b_left", 0.035, "m", "face width of the left helix half"),
    _p("b_right", 0.035, "m", "face width of the right helix half"),
    _p("groove", 0.010, "m", "groove width between the helix halves", allowed=NON_NEGATIVE),
    _p("a_left", 0.020, "m", "distance from the left bearing to the outer face of the left half",
       allowed=NON_NEGATIVE, component="bearings"),
    _p("a_right", 0.020, "m", "distance from the right bearing to the outer face of the right half",
       allowed=NON_NEGATIVE, component="bearings"),
    # mesh (section 3)
    _p("c_point", 2.5e8, "N/m", "stiffness of one contact point"),
    _p("eps_q", 0.8, "1", "phase overlap of the two lines of engagement, fraction of p_x",
       allowed=FRACTION),
    _p("stagger", 0.0, "1", "shift of the right half against the left, fraction of p_x",
       allowed=FRACTION),
    _p("phase0", 0.0, "1", "position of the first contact point at t = 0, fraction of p_x",
       allowed=FRACTION),
    _p("edge_ramp", 0.0, "m", "half-length of the contact ellipse along the axis (0: sharp edges)",
       allowed=NON_NEGATIVE),
    _p("contact_loss", True, "", "teeth can separate (a point carries no tensile force)", bool,
       allowed=FINITE),
    _p("zeta_mesh", 0.05, "1", "mesh damping ratio", allowed=NON_NEGATIVE),
    _p("dbeta_left", 0.0, "rad", "helix (lead) error of the left half", allowed=FINITE),
    _p("dbeta_right", 0.0, "rad", "helix (lead) error of the right half", allowed=FINITE),
    # inertias (section 1)
    _p("I_pinion", 2.18927e-4, "kg.m2", "polar moment of inertia of the pinion"),
    _p("I_wheel", 0.0367713, "kg.m2", "polar moment of inertia of the wheel"),
    _p("m_pinion", 0.929436, "kg", "mass of the pinion", component="bearings"),
    _p("m_wheel", 12.0455, "kg", "mass of the wheel", component="bearings"),
    _p("J_pinion", None, "kg.m2", "transverse moment of inertia of the pinion "
       "(default: solid cylinder m(3R^2+L^2)/12)", component="bearings"),
    _p("J_wheel", None, "kg.m2", "transverse moment of inertia of the wheel "
       "(default: solid cylinder m(3R^2+L^2)/12)", component="bearings"),
    _p("I_motor", 0.05, "kg.m2", "moment of inertia of the motor rotor", component="motor"),
    _p("I_load", 0.5, "kg.m2", "moment of inertia of the load", component="load"),
    # shafts and bearings (section 4)
    _p("C_shaft_in", 5e4, "N.m/rad", "torsional stiffness of the input shaft", component="motor"),
    _p("h_shaft_in", 1.0, "N.m.s/rad", "torsional damping of the input shaft",
       allowed=NON_NEGATIVE, component="motor"),
    _p("C_shaft_out", 2e5, "N.m/rad", "torsional stiffness of the output shaft", component="load"),
    _p("h_shaft_out", 1.0, "N.m.s/rad", "torsional damping of the output shaft",
       allowed=NON_NEGATIVE, component="load"),
    *[_p(f"c_brg_{gear}_{side}", 5e8, "N/m", f"stiffness of the {side} {gear} bearing",
         component="bearings")
      for gear in ("pinion", "wheel") for side in ("left", "right")],
    *[_p(f"h_brg_{gear}_{side}", 2000.0, "N.s/m", f"damping of the {side} {gear} bearing",
         allowed=NON_NEGATIVE, component="bearings")
      for gear in ("pinion", "wheel") for side in ("left", "right")],
    # initial state (section 6)
    _p("w0_pinion", 157.08, "rad/s", "pinion speed at t = 0", allowed=PINION_SPEED),
]}

# The inputs of the train (section 5): torques held constant over a communication step.
INPUTS: dict[str, Parameter] = {p.name: p for p in [
    _p("M_motor", 500.0, "N.m", "motor torque, drives the motor rotor (the pinion without a motor)",
       allowed=FINITE),
    _p("M_load", 1800.0, "N.m", "load torque, resists the load (the wheel without a load)",
       allowed=FINITE),
]}


def parameters_of(components: dict[str, bool]) -> dict[str, Parameter]:
    """The parameters that a train with these components carries."""
    return {name: p for name, p in PARAMETERS.items()
            if p.component is None or components[p.component]}


def with_unit(text: str, unit: str) -> str:
    """`text` followed by its `unit` as messages write it ("22.86 rad"); a pure number (unit
    "1" or "") gets none."""
    if unit in ("", "1"):
        return text
    return f"{text} {unit}"


def allowed_words(allowed: Range, unit: str = "", whole: bool = False, infinite: bool = False,
                  meaning: str = "") -> str:
    """What `allowed` admits, as messages say it, with the unit: "> 0 N/m and finite",
    "(0, 1.5708) rad, an angle in radians", "any finite number, in N.m". A range open at an
    end says "and finite" (Range.contains refuses inf, which "> 0" alone would seem to admit),
    unless `infinite` (+inf allowed too: "or inf") or `whole` (a whole number is finite);
    `meaning` closes it in parentheses."""
    bounded = allowed.low is not None or allowed.high is not None
    described = with_unit(allowed.describe(), unit) if bounded or unit in ("", "1") \
        else f"{allowed.describe()}, in {unit}"
    if infinite:
        described += " or inf"
    elif bounded and (allowed.low is None or allowed.high is None) and not whole:
        described += " and finite"
    described = f"a whole number {described}" if whole else described
    described += ", an angle in radians" if unit == "rad" else ""
    return described + (f" ({meaning})" if meaning else "")


def number_problem(value, allowed: Range, unit: str = "", whole: bool = False,
                   infinite: bool = False, meaning: str = "") -> str | None:
    """Why `value` is not an allowed number, or None: the one check of a number against its
    range, for the parameters and inputs of a scene (check_value) and the run arguments
    (herringbone.arguments.Argument). The message gives the value and what is allowed with
    the unit ("is 22.86 rad; allowed: (0, 1.5708) rad, an angle in radians"; allowed_words);
    `whole`: a whole number; `infinite`: +inf allowed too ("no limit"); `meaning` closes it in
    parentheses."""
    described = allowed_words(allowed, unit, whole, infinite, meaning)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return f"must be a number, got {type(value).__name__} {value!r}; allowed: {described}"
    number = float(value)
    fits = (infinite and number == math.inf) or allowed.contains(number)
    if not fits or (whole and number != int(number)):
        shown = with_unit(repr(value), unit) if math.isfinite(number) else repr(value)
        return f"is {shown}; allowed: {described}"
    return None


def is_flag(value) -> bool:
    """Whether `value` is true or false: a bool, or numpy's (np.bool_, which is no bool)."""
    return isinstance(value, (bool, np.bool_))


def check_value(parameter: Parameter, value) -> str | None:
    """Why `value` is not allowed for `parameter`, or None if it is (number_problem, with the
    parameter's unit; a flag must be true or false, and the message says what it got)."""
    if parameter.kind is bool:
        return None if is_flag(value) \
            else f"must be true or false, got {type(value).__name__} {value!r}"
    return number_problem(value, parameter.allowed, parameter.unit, whole=parameter.kind is int)


def values_problem(name: str, values) -> str | None:
    """Why a value of the parameter or input `name` among `values` (a sweep's, a
    continuation's) is not allowed, the first one, as "NAME is VALUE; allowed: …", or None."""
    parameter = {**PARAMETERS, **INPUTS}[name]
    for value in values:
        problem = check_value(parameter, float(value))
        if problem is not None:
            return f"{name} {problem}"
    return None


def name_with_unit(name: str) -> str:
    """A table column's header: the name and its SI unit, "F_mesh [N]"; pure numbers
    ("n_contacts", "z_pinion") and unknown names bare."""
    unit = unit_of(name)
    return f"{name} [{unit}]" if unit not in ("", "1") else name


def unit_of(name: str) -> str:
    """The unit of a parameter, input or output by name ("" if it has none or is unknown)."""
    for table in (PARAMETERS, INPUTS, OUTPUTS):
        if name in table:
            return table[name].unit
    return "s" if name == "time" else ""


@dataclass(frozen=True)
class Output:
    """One output of the train: its name, unit, meaning, type, the component a scene needs to
    have it, and where the compiled equations.outputs puts its value (GearTrainModel.
    output_layout reads `slot` and `rate_of`; neither: the output is the force of the shaft or
    bearing of the same name)."""

    name: str
    unit: str
    description: str
    kind: type = float
    component: str | None = None  # None: every scene has it
    slot: str | None = None  # the constant of model/equations.py naming its entry
    rate_of: str | None = None  # the coordinate whose rate it is (speeds)


# The outputs of docs/model.md section 7, in the order a scene lists them; the one list of them:
# model.assembly.output_names picks those a scene has, GearTrainModel.output_layout places them,
# the FMU declares them, docs/model.md section 12 tables them.
OUTPUTS: dict[str, Output] = {o.name: o for o in [
    Output("k_mesh", "N/m", "mesh stiffness: sum of the stiffnesses of the points in contact",
           slot="K_MESH"),
    Output("k_mesh_left", "N/m", "mesh stiffness of the left half", slot="K_MESH_LEFT"),
    Output("k_mesh_right", "N/m", "mesh stiffness of the right half", slot="K_MESH_RIGHT"),
    Output("F_mesh", "N", "mesh force: sum of the contact point forces", slot="F_MESH"),
    Output("F_mesh_left", "N", "mesh force of the left half", slot="F_MESH_LEFT"),
    Output("F_mesh_right", "N", "mesh force of the right half", slot="F_MESH_RIGHT"),
    *[Output(f"F_brg_{gear}_{side}", "N", f"reaction of the {side} {gear} bearing "
             "(pinion bearings sum to -F_mesh, wheel bearings to +F_mesh)",
             component="bearings")
      for gear in ("pinion", "wheel") for side in ("left", "right")],
    Output("w_motor", "rad/s", "motor speed", component="motor", rate_of="phi_motor"),
    Output("w_pinion", "rad/s", "pinion speed", rate_of="phi_pinion"),
    Output("w_wheel", "rad/s", "wheel speed (positive in its running direction)",
           rate_of="phi_wheel"),
    Output("w_load", "rad/s", "load speed", component="load", rate_of="phi_load"),
    Output("T_shaft_in", "N.m", "input shaft torque", component="motor"),
    Output("T_shaft_out", "N.m", "output shaft torque", component="load"),
    Output("dte", "m", "dynamic transmission error Rp*phi_p - Rw*phi_w", slot="DTE"),
    Output("n_contacts", "1", "number of contact points carrying load", int,
           slot="N_CONTACTS"),
]}


def outputs_of(components: dict[str, bool]) -> dict[str, Output]:
    """The outputs that a train with these components has, in the order of OUTPUTS."""
    return {name: o for name, o in OUTPUTS.items()
            if o.component is None or components[o.component]}
