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
        """The interval in words, as messages show it: "> 0", "[1e-12, 0.01]", "[0, 1)"."""
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
FRACTION = Range(0.0, 1.0, high_open=True)  # of the axial pitch p_x (FRACTION_MEANING)
FRACTION_MEANING = "a fraction of the axial pitch p_x"
FINITE = Range()
# a tooth count: a ring gear of a thousand teeth is beyond any gearbox this model describes,
# and 1e20 teeth were taken and failed at the first step ("step size fell below the time's
# resolution") with pitch radii of 2e17 m
TOOTH_COUNT = Range(1, 1000)
# |w0_pinion| (rad/s): 1e5 is 955 000 rpm, a rim speed of 2 km/s on the reference pinion, past
# any gear; 1e12 rad/s was taken and ran 1.6e8 mesh periods in 1e-4 s, the run looking hung
PINION_SPEED = Range(-1e5, 1e5)
# The sizes and properties of a gear train of any practical size, from a micro gear of
# micrometre module to a mill drive ten times the largest built (docs/model.md section 12 gives
# each bound's reason). Beyond them a run is meaningless (beta = 1e-30: no point ever on the
# face; c_point = 1: a static deflection of 3.8 km), endless (c_point of 9.2e18; m_n = 1e-30:
# 1e27 contact points a face) or fails inside (1e±300: division by zero, overflow, "SVD did
# not converge"). What the ranges cannot hold on their own, values
# that do not go together, scene.py checks: a face of at most 200 axial pitches, an edge ramp
# of at most half the face, elements that ring and damp at most 1e8 rad/s and 1e9 1/s. The
# FMU declares these bounds as its min and max.
# beta (rad), 0.01-1.4 (0.57°-80°): below, the axial pitch π·m_n/sin β passes 300 modules,
# a spur gear the travelling points do not describe; above, the radii z·m_n/(2 cos β) run away
HELIX_ANGLE = Range(0.01, 1.4)
# m_n (m): 1 µm, a MEMS gear's, to 1 m, ten times a mill gear's
MODULE = Range(1e-6, 1.0)
# face widths (m): 1 µm to 10 m, five times a mill gear's face
LENGTH = Range(1e-6, 10.0)
# groove, bearing distances (m): up to 10 m
GAP = Range(0.0, 10.0)
# edge_ramp (m): at most half the widest face (scene.py holds it to half the narrower one)
RAMP = Range(0.0, 5.0)
# a point's or a bearing's stiffness (N/m): 1e3, under a MEMS gear's tooth, to 1e13, a thousand
# times a metre-wide mill gear's (the reference's: 2.5e8 and 5e8)
STIFFNESS = Range(1e3, 1e13)
# a shaft (N.m/rad): 1e-6, a steel wire of 50 µm and 5 cm, to 1e11, a steel shaft 1 m thick
# and 8 cm long (the reference's: 5e4 and 2e5)
TORSIONAL_STIFFNESS = Range(1e-6, 1e11)
# dampings: a few times the critical damping 2·sqrt(c·m) of the stiffest element on the heaviest
# body (the reference's: 1 N.m.s/rad and 2000 N.s/m)
BEARING_DAMPING = Range(0.0, 1e11)
TORSIONAL_DAMPING = Range(0.0, 1e10)
# dbeta_* (rad): 0.1, a quarter of the reference's helix; a ground gear's are under 1e-4
LEAD_ERROR = Range(-0.1, 0.1)
# zeta_mesh: ten times critical (gear meshes damp 0.02-0.2)
DAMPING_RATIO = Range(0.0, 10.0)
# masses (kg): 1e-9, a steel gear of 50 µm, to 1e7, fifty times the heaviest gear wheel
MASS = Range(1e-9, 1e7)
# moments of inertia (kg.m2): 1e-18, a gear of 10 µm module, to 1e8, twenty times the ring
# gear of a 14 m mill
INERTIA = Range(1e-18, 1e8)
# a lead error is a slope, which small-angle usage writes in rad
LEAD_ERROR_MEANING = ("a slope, the lead deviation per unit of axial travel f_Hb/b: 10 µm over "
                      "35 mm is 2.86e-4")


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
    _p("m_n", 0.004, "m", "normal module", allowed=MODULE),
    _p("beta", 0.398982, "rad", "helix angle on the pitch cylinder", allowed=HELIX_ANGLE),
    _p("b_left", 0.035, "m", "face width of the left helix half", allowed=LENGTH),
    _p("b_right", 0.035, "m", "face width of the right helix half", allowed=LENGTH),
    _p("groove", 0.010, "m", "groove width between the helix halves", allowed=GAP),
    _p("a_left", 0.020, "m", "distance from the left bearing to the outer face of the left half",
       allowed=GAP, component="bearings"),
    _p("a_right", 0.020, "m", "distance from the right bearing to the outer face of the right half",
       allowed=GAP, component="bearings"),
    # mesh (section 3)
    _p("c_point", 2.5e8, "N/m", "stiffness of one contact point", allowed=STIFFNESS),
    _p("eps_q", 0.8, "1", "phase overlap of the two lines of engagement, fraction of p_x",
       allowed=FRACTION),
    _p("stagger", 0.0, "1", "shift of the right half against the left, fraction of p_x",
       allowed=FRACTION),
    _p("phase0", 0.0, "1", "position of the first contact point at t = 0, fraction of p_x",
       allowed=FRACTION),
    _p("edge_ramp", 0.0, "m", "half-length of the contact ellipse along the axis (0, or under "
       "1e-8 of the wider face: sharp edges)", allowed=RAMP),
    _p("contact_loss", True, "", "teeth can separate (a point carries no tensile force)", bool,
       allowed=FINITE),
    _p("zeta_mesh", 0.05, "1", "mesh damping ratio", allowed=DAMPING_RATIO),
    _p("dbeta_left", 0.0, "rad", "lead error of the left half: deviation per axial travel, "
       "f_Hb/b", allowed=LEAD_ERROR),
    _p("dbeta_right", 0.0, "rad", "lead error of the right half: deviation per axial travel, "
       "f_Hb/b", allowed=LEAD_ERROR),
    # inertias (section 1)
    _p("I_pinion", 2.18927e-4, "kg.m2", "polar moment of inertia of the pinion",
       allowed=INERTIA),
    _p("I_wheel", 0.0367713, "kg.m2", "polar moment of inertia of the wheel", allowed=INERTIA),
    _p("m_pinion", 0.929436, "kg", "mass of the pinion", allowed=MASS, component="bearings"),
    _p("m_wheel", 12.0455, "kg", "mass of the wheel", allowed=MASS, component="bearings"),
    _p("J_pinion", None, "kg.m2", "transverse moment of inertia of the pinion "
       "(default: solid cylinder m(3R^2+L^2)/12)", allowed=INERTIA, component="bearings"),
    _p("J_wheel", None, "kg.m2", "transverse moment of inertia of the wheel "
       "(default: solid cylinder m(3R^2+L^2)/12)", allowed=INERTIA, component="bearings"),
    _p("I_motor", 0.05, "kg.m2", "moment of inertia of the motor rotor", allowed=INERTIA,
       component="motor"),
    _p("I_load", 0.5, "kg.m2", "moment of inertia of the load", allowed=INERTIA,
       component="load"),
    # shafts and bearings (section 4)
    _p("C_shaft_in", 5e4, "N.m/rad", "torsional stiffness of the input shaft",
       allowed=TORSIONAL_STIFFNESS, component="motor"),
    _p("h_shaft_in", 1.0, "N.m.s/rad", "torsional damping of the input shaft",
       allowed=TORSIONAL_DAMPING, component="motor"),
    _p("C_shaft_out", 2e5, "N.m/rad", "torsional stiffness of the output shaft",
       allowed=TORSIONAL_STIFFNESS, component="load"),
    _p("h_shaft_out", 1.0, "N.m.s/rad", "torsional damping of the output shaft",
       allowed=TORSIONAL_DAMPING, component="load"),
    *[_p(f"c_brg_{gear}_{side}", 5e8, "N/m", f"stiffness of the {side} {gear} bearing",
         allowed=STIFFNESS, component="bearings")
      for gear in ("pinion", "wheel") for side in ("left", "right")],
    *[_p(f"h_brg_{gear}_{side}", 2000.0, "N.s/m", f"damping of the {side} {gear} bearing",
         allowed=BEARING_DAMPING, component="bearings")
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
                  meaning: str = "", zero: bool = False) -> str:
    """What `allowed` admits, as messages say it, with the unit: "> 0 N/m and finite",
    "[0.01, 1.4] rad, an angle in radians", "any finite number, in N.m". A range open at an
    end says "and finite" (Range.contains refuses inf, which "> 0" alone would seem to admit),
    unless `infinite` (+inf allowed too: "or inf") or `whole` (a whole number is finite);
    `zero`: 0 allowed too ("0, >= 1e-12 or inf"); `meaning` closes it in parentheses."""
    bounded = allowed.low is not None or allowed.high is not None
    described = with_unit(allowed.describe(), unit) if bounded or unit in ("", "1") \
        else f"{allowed.describe()}, in {unit}"
    if infinite:
        described += " or inf"
    elif bounded and (allowed.low is None or allowed.high is None) and not whole:
        described += " and finite"
    described = f"a whole number {described}" if whole else described
    described = f"0, {described}" if zero else described
    described += ", an angle in radians" if unit == "rad" and not meaning else ""
    return described + (f" ({meaning})" if meaning else "")


def number_problem(value, allowed: Range, unit: str = "", whole: bool = False,
                   infinite: bool = False, meaning: str = "", zero: bool = False) -> str | None:
    """Why `value` is not an allowed number, or None: the one check of a number against its
    range, for the parameters and inputs of a scene (check_value) and the run arguments
    (herringbone.arguments.Argument). The message gives the value and what is allowed with
    the unit ("is 22.86 rad; allowed: [0.01, 1.4] rad, an angle in radians"; allowed_words);
    `whole`: a whole number; `infinite`: +inf allowed too ("no limit"); `zero`: 0 allowed
    too (a "no limit" a start value can say); `meaning` closes it in parentheses."""
    described = allowed_words(allowed, unit, whole, infinite, meaning, zero)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return f"must be a number, got {type(value).__name__} {value!r}; allowed: {described}"
    number = as_float(value)
    if not isinstance(number, float):  # a Python int past the largest float (10**400)
        return f"is {short_repr(value)}, too large for a float; allowed: {described}"
    fits = (infinite and number == math.inf) or (zero and number == 0.0) \
        or allowed.contains(number)
    if not fits or (whole and number != int(number)):
        shown = with_unit(short_repr(value), unit) if math.isfinite(number) else repr(value)
        return f"is {shown}; allowed: {described}"
    return None


def short_repr(value) -> str:
    """repr(value) as a message shows it, but an integer of more than 20 digits by its size
    ("an integer of 401 digits"): 10**400 was echoed whole, and repr() of one of over 4300
    digits raises."""
    if _is_long_integer(value):
        digits = math.floor(math.log10(abs(int(value)))) + 1
        return f"{'a negative' if value < 0 else 'an'} integer of {digits} digits"
    return repr(value)


def _is_long_integer(value) -> bool:
    """Whether `value` is an integer of more than 20 digits (short_repr abbreviates it)."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool) \
        and abs(int(value)) >= 10 ** 20


def typed_repr(value) -> str:
    """A value with its type, as a message shows what it got: "str 'yes'"; an integer of more
    than 20 digits as short_repr gives it."""
    return short_repr(value) if _is_long_integer(value) \
        else f"{type(value).__name__} {value!r}"


def is_flag(value) -> bool:
    """Whether `value` is true or false: a bool, or numpy's (np.bool_, which is no bool)."""
    return isinstance(value, (bool, np.bool_))


def check_value(parameter: Parameter, value) -> str | None:
    """Why `value` is not allowed for `parameter`, or None if it is (number_problem, with the
    parameter's unit; a flag must be true or false, and the message says what it got)."""
    if parameter.kind is bool:
        return None if is_flag(value) \
            else f"must be true or false, got {typed_repr(value)}"
    meaning = {id(FRACTION): FRACTION_MEANING, id(LEAD_ERROR): LEAD_ERROR_MEANING}
    return number_problem(value, parameter.allowed, parameter.unit, whole=parameter.kind is int,
                          meaning=meaning.get(id(parameter.allowed), ""))


def values_problem(name: str, values) -> str | None:
    """Why a value of the parameter or input `name` among `values` (a sweep's, a
    continuation's) is not allowed, the first one, as "NAME is VALUE; allowed: …", or None."""
    parameter = {**PARAMETERS, **INPUTS}[name]
    for value in values:
        problem = check_value(parameter, as_float(value))
        if problem is not None:
            return f"{name} {problem}"
    return None


def as_float(value):
    """float(value), or `value` itself where it is too large for a float (an int of 10**400),
    for number_problem to say so (float() raises OverflowError there)."""
    try:
        return float(value)
    except OverflowError:
        return value


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
    *[Output(f"F_brg_{gear}_{side}", "N", f"reaction of the {side} {gear} bearing along the "
             "mesh force, the model's one plane (in static equilibrium the pinion bearings "
             "sum to -F_mesh, the wheel bearings to +F_mesh; in motion the bodies' inertia "
             "takes its part)",
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
