"""`herringbone info SCENE`: geometry, mesh phasing, natural modes and resonance speeds of a scene.

The natural modes come from herringbone.model.assembly at the stiffness averaged over one mesh
period.
Output is plain ASCII so that any console shows it.
"""
from __future__ import annotations

import math

import numpy as np

from ..model.assembly import GearTrainModel, mass_matrix, natural_modes, rigid_rotation_mode
from ..model.geometry import GearGeometry
from ..model.mesh import Mesh
from ..model.parameters import RPM_PER_RAD_S
from .excitation import HARMONICS_CONSIDERED, resonance_lines, strongest
from .phasing import scene_phasing, without_contact_note
from .steady_state import unbalance_lines

HARMONICS = (1, 2, 3)
MAX_RPM = 30_000.0  # resonance speeds above this are not listed: beyond any practical pinion speed
COORDINATE_KINDS = {"phi": "torsional", "psi": "tilt", "x": "lateral"}
STREAM_NAMES = ("left pre-pole", "left post-pole", "right pre-pole", "right post-pole")


def mode_character(mode_shape, masses, coordinate_names) -> str:
    """The kind of coordinate (torsional phi_*, tilt psi_*, lateral x_*) holding the largest
    share of an elastic mode's kinetic energy m_i·v_i², and that share."""
    energy = np.asarray(masses) * np.asarray(mode_shape) ** 2
    shares: dict[str, float] = {}
    for name, e in zip(coordinate_names, energy):
        kind = COORDINATE_KINDS[name.split("_")[0]]
        shares[kind] = shares.get(kind, 0.0) + float(e / energy.sum())
    kind = max(shares, key=lambda k: shares[k])
    return f"{kind} ({100.0 * shares[kind]:.0f} % of kinetic energy)"


def _mode_lines(frequencies, shapes, masses, names, rigid) -> list[str]:
    """The lines of the natural frequencies: the rigid rotation first (column `rigid` of
    `shapes`, at 0 Hz), then the elastic modes ascending. Where an elastic mode is as slow
    as the rounding of a zero, the eigensolver may return either of the two as the slower,
    so the rigid rotation is not told by its place."""
    elastic = [i for i in np.argsort(frequencies, kind="stable") if i != rigid]
    return [_mode_line(1, 0.0, "rigid rotation")] + [
        _mode_line(number, frequencies[i], mode_character(shapes[:, i], masses, names),
                   frequencies.max())
        for number, i in enumerate(elastic, start=2)]


def _mode_line(number, frequency_hz, character, fastest_hz=0.0) -> str:
    """A line of the natural frequencies: a mode below 0.01 Hz by its significant digits,
    and where rounding blurs it beside the fastest mode (`fastest_hz`; 0: the rigid
    rotation's line, which is not blurred) by more than 0.1 %, by how much; an elastic
    mode whose ω² rounded to zero or below is all rounding."""
    shown = f"{frequency_hz:12.2f}" if frequency_hz == 0.0 or frequency_hz >= 0.01 \
        else f"{frequency_hz:12.3g}"
    line = f"  {number:2d} {shown} Hz  {character}"
    blur = (0.0 if fastest_hz <= 0.0 else math.inf if frequency_hz <= 0.0
            else rounding_share(frequency_hz, fastest_hz))
    if blur >= 1.0:
        return f"{line}; rounding beside {fastest_hz:.0f} Hz, not a frequency: too slow to resolve"
    if blur > 1e-3:
        return f"{line}; ±{100 * blur:.2g} % by rounding beside {fastest_hz:.0f} Hz"
    return line


def rounding_share(frequency_hz, fastest_hz) -> float:
    """How far rounding may move a natural frequency, as a share of it: an eigenvalue ω² is
    resolved to about machine epsilon times the largest, so f to half that over f²."""
    return 0.5 * float(np.finfo(float).eps) * (fastest_hz / frequency_hz) ** 2


def resonance_speeds(frequency_hz: float, z_pinion: int) -> dict[int, float]:
    """Pinion speeds (rad/s) at which k·f_mesh = f_n, f_mesh = ω·zp/(2π), for k in HARMONICS."""
    return {k: 2.0 * math.pi * frequency_hz / (k * z_pinion) for k in HARMONICS}


def scene_report(scene) -> str:
    """The text of `herringbone info` for a Scene."""
    p = scene.parameters
    g = GearGeometry.from_parameters(p)
    phasing = scene_phasing(p)
    mesh = Mesh(p)
    lines = [f"Scene {scene.name} ({scene.source})", "",
             "Geometry",
             f"  pinion radius Rp       {1e3 * g.radius_pinion:.3f} mm",
             f"  wheel radius Rw        {1e3 * g.radius_wheel:.3f} mm",
             f"  ratio u = zw/zp        {g.ratio:.4g} ({g.z_wheel}/{g.z_pinion})",
             f"  axial pitch p_x        {1e3 * g.axial_pitch:.3f} mm",
             f"  eps_beta left, right   {phasing.eps_beta_left:.4f}, {phasing.eps_beta_right:.4f}",
             f"  q21 = eps_q*p_x        {1e3 * phasing.q21:.3f} mm (eps_q {p['eps_q']:g})", "",
             "Contact points on the face (the phasing law: every point loaded, sharp edges)",
             "  stream (eps, delay in mesh periods):"]
    lines += [f"    {name:<16} {eps:.4f}, {delay:.4f}"
              for name, (eps, delay) in zip(STREAM_NAMES, phasing.streams)]
    lines += [f"  alternation law        {phasing.law} (read from phase 0)",
              f"  K_eps                  {phasing.k_eps} points (K_eps/eps_beta per half "
              f"{phasing.k_eps_ratio:.3f})"]
    gap = without_contact_note(mesh)
    if gap:
        lines.append(f"  ({gap})")
    if p["edge_ramp"] > 0:
        lines.append(f"  (edge_ramp {1e3 * p['edge_ramp']:g} mm widens each point's span: the "
                     "model counts more points than this law)")
    if p["contact_loss"]:
        lines.append("  (contact_loss: a point whose teeth part carries no load, so a run may "
                     "load fewer points than this law)")
    # the speed as the scene gives it (w0_pinion < 0 turns backwards); a frequency has no sign
    speed = p["w0_pinion"]
    f_mesh = abs(speed) * g.z_pinion / (2.0 * math.pi)
    lines += ["", f"Mesh frequency at w0_pinion = {speed:g} rad/s "
                  f"({speed * RPM_PER_RAD_S:.0f} rpm): {f_mesh:.2f} Hz",
              *unbalance_lines(scene), ""]
    frequencies, shapes, names = natural_modes(scene, pinion_angle=None)
    masses = np.diag(mass_matrix(scene))
    rigid = rigid_rotation_mode(shapes, masses, GearTrainModel(scene).rigid_rotation)
    lines += [f"Natural frequencies at the mean mesh stiffness {mesh.mean_stiffness():.4g} N/m",
              *_mode_lines(frequencies, shapes, masses, names, rigid)]
    lines += ["", f"Resonances: pinion speed at which k*f_mesh meets f_n, rpm (rad/s), k up to "
                  f"{HARMONICS[-1]} (higher harmonics ring too: below); speeds above "
                  f"{MAX_RPM:.0f} rpm are not listed",
              "  f_n / Hz    " + "".join(f"{f'k = {k}':<22}" for k in HARMONICS)]
    for f in np.delete(frequencies, rigid):
        if f <= 0.0 or rounding_share(f, frequencies.max()) >= 1.0:
            continue  # not a frequency (its line says so)
        speeds = resonance_speeds(f, g.z_pinion)
        cells = [f"{w * RPM_PER_RAD_S:.0f} ({w:.1f})" if w * RPM_PER_RAD_S <= MAX_RPM else "-"
                 for w in speeds.values()]
        if any(cell != "-" for cell in cells):
            lines.append(f"  {f:10.2f}  " + "".join(f"{cell:<22}" for cell in cells))
    return "\n".join(lines + _ringing_lines(scene, frequencies, shapes, masses, names)) + "\n"


RINGING_LISTED = 8  # the strongest resonances `info` lists


def _ringing_lines(scene, frequencies, shapes, masses, names) -> list[str]:
    """The strongest resonances below MAX_RPM (excitation.strongest), each with its mode."""
    def name_of(frequency_hz):
        nearest = int(np.argmin(np.abs(frequencies - frequency_hz)))
        return mode_character(shapes[:, nearest], masses, names).split(" (")[0] + " mode"

    found = strongest(scene, MAX_RPM / RPM_PER_RAD_S, RINGING_LISTED)
    return ["", "Resonances that ring, strongest first: the mesh force's k-th harmonic there, "
                f"a share of the static mesh force (k up to {HARMONICS_CONSIDERED}; a "
                "first-order estimate, herringbone.analysis.excitation)",
            *(resonance_lines(found, name_of) if found else ["  none of 2 % or more"])]
