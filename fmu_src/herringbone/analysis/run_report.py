"""What `herringbone run` writes and prints about a run: the CSV of its outputs (a header of
names with units), the summary table (with a unit column) and, with --plot, its pictures."""
from __future__ import annotations

import csv
import math
from pathlib import Path

from ..files import replace_file
from ..model.parameters import RPM_PER_RAD_S, name_with_unit, unit_of

# outputs shown in the summary in a unit more readable than SI: name -> (unit, factor)
SHOWN_IN = {"dte": ("um", 1e6)}


def write_csv(results: dict, path: Path) -> None:
    """A run's outputs ({name: samples}) as CSV, one column a name with its unit ("time [s]",
    "F_mesh [N]"), 12 significant digits; the folder is made as needed, the file written
    whole or not at all (files.replace_file: a long table takes seconds to write)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    names = list(results)

    def write(staging: Path) -> None:
        with open(staging, "w", newline="") as file:
            writer = csv.writer(file)
            writer.writerow([name_with_unit(name) for name in names])
            for row in zip(*(results[name] for name in names)):
                writer.writerow([f"{value:.12g}" for value in row])

    replace_file(path, write)


def summary(scene, results: dict, wall_time: float, integrator: str = "",
            start_time: float | None = None) -> str:
    """A few lines on a finished run: its span, the static mesh force, a table of each output
    (with its unit) at the start, its least and largest sample and at the end, and the time
    it took (`integrator`: what ran it, in words; `start_time`: the part of `wall_time`, s,
    before the first step, None where it is not known)."""
    from ..model.assembly import GearTrainModel

    model = GearTrainModel(scene)
    stop = results["time"][-1]
    by = f" on {integrator}" if integrator else ""
    lines = [f"scene {scene.name} ({scene.source}): {model.size} degrees of freedom "
             f"({', '.join(model.coordinates)})",
             f"simulated {stop:g} s{by} in {_wall_time(stop, wall_time, start_time)}",
             *_start_lines(scene, model, results),
             # no mean: samples synchronous with the mesh period alias its fast content
             f"{'output':<20}{'unit':<8}{'at t=0':>14}{'min of samples':>16}"
             f"{'max of samples':>16}{'at the end':>14}"]
    for name, values in results.items():
        if name != "time":
            unit, factor = SHOWN_IN.get(name, (unit_of(name), 1.0))
            shown = values * factor
            lines.append(f"{name:<20}{unit:<8}{shown[0]:>14.6g}{shown.min():>16.6g}"
                         f"{shown.max():>16.6g}{shown[-1]:>14.6g}")
    return "\n".join(lines)


def _start_lines(scene, model, results: dict) -> list[str]:
    """The static mesh force and what the run's start says of the scene: back flanks loaded,
    points in tension, a face without contact, torques that do not balance, deflections that
    are not small (each only where it holds)."""
    from .steady_state import unbalance_lines

    static = model.static_mesh_force()
    return [f"static mesh force M_motor/Rp = {static:.1f} N" + _back_flanks(static)
            + _tension_at_start(static, results["F_mesh"][0]),
            *_without_contact(model.mesh), *unbalance_lines(scene),
            *_large_deflection(scene.parameters["m_n"], results["dte"][0])]


def _back_flanks(static_force: float) -> str:
    """What a negative static mesh force (N) means for the run: M_motor < 0 presses the back
    flanks together, on which the model has no contact (docs/model.md section 3), so the
    teeth separate while it lasts; '' for a force >= 0."""
    if static_force >= 0.0:
        return ""
    return (" (negative: M_motor < 0 loads the back flanks, on which the model has no "
            "contact: the teeth separate)")


def _tension_at_start(static_force: float, start_force: float) -> str:
    """Why F_mesh (N) starts away from the static mesh force (N) of a torque that presses the
    teeth: the start's equilibrium, every point loaded, leaves points in tension that start
    unloaded (docs/model.md section 6); '' where it starts on it (to 1e-6)."""
    if static_force <= 0.0 or abs(start_force - static_force) <= 1e-6 * static_force:
        return ""
    return (f"; F_mesh starts at {start_force:.1f} N: the start's static equilibrium (every "
            "point loaded) leaves points in tension, which start unloaded, and the run starts "
            "with a transient")


# a static transmission error past this share of the normal module is no small deflection
LARGE_DEFLECTION = 0.1


def _large_deflection(module: float, start_dte: float) -> list[str]:
    """A line where the start's static transmission error (m) is not small beside the tooth,
    over LARGE_DEFLECTION of the normal module (m): the model's linear contact springs and
    fixed lever arms hold for deflections far under the tooth's size (bearings of 1e4 N/m
    deflected 1.15 m and gave a dte of 2.3 m without a word)."""
    if abs(start_dte) <= LARGE_DEFLECTION * module:
        return []
    return [f"The static deflection is not small: dte {1e6 * start_dte:.4g} µm at the start, "
            f"{abs(start_dte) / module:.3g} times the normal module m_n = {1e3 * module:g} mm; "
            "the model holds for deflections far under the tooth's size"]


def _without_contact(mesh) -> list[str]:
    """phasing.without_contact_note as the summary's line, where the face leaves the pair
    without contact for part of each mesh period."""
    from .phasing import without_contact_note

    note = without_contact_note(mesh)
    return [note[0].upper() + note[1:]] if note else []


def _wall_time(stop: float, wall_time: float, start_time: float | None) -> str:
    """How long a run of `stop` simulated s took, in words: the start (the model's tables,
    the compiled code loaded: a fixed cost that a short run's rate would hide the stepping
    under) apart from the stepping and its rate, where the start is known."""
    if start_time is None:
        return (f"{wall_time:.2f} s of wall time, start included "
                f"({wall_time / stop:.2f} s per simulated second)")
    stepping = wall_time - start_time
    return (f"{wall_time:.2f} s of wall time: {start_time:.2f} s to start (the model's tables, "
            f"the compiled code loaded), {stepping:.3g} s stepping "
            f"({stepping / stop:.3g} s per simulated second)")


def plot_run(scene, results, csv_path: Path) -> list[Path]:
    """`run --plot`: time histories and amplitude spectra beside the run's CSV,
    <stem>_time.png and <stem>_spectrum.png; returns their paths. The spectra take the
    largest whole number of mesh periods in the second half of the run, at its end
    (plots.whole_mesh_periods: the mesh harmonics on the spectrum's bins)."""
    from .campbell import elastic_frequencies
    from .plots import plot_spectra, plot_time_histories, whole_mesh_periods

    stem = csv_path.with_suffix("")
    histories, spectra = Path(f"{stem}_time.png"), Path(f"{stem}_spectrum.png")
    speed = abs(scene.parameters["w0_pinion"])
    plot_time_histories(results, histories, f"{scene.name}: time histories "
                        f"(w0 {speed * RPM_PER_RAD_S:.0f} rpm)")
    mesh_frequency = speed * scene.parameters["z_pinion"] / (2.0 * math.pi)
    keep, periods = whole_mesh_periods(results["time"], mesh_frequency)
    counted = f"{periods} mesh period{'' if periods == 1 else 's'}"
    plot_spectra(results, spectra, mesh_frequency, elastic_frequencies(scene),
                 f"{scene.name}: amplitude spectra, the last {counted} of the run "
                 f"(f_mesh {mesh_frequency:.1f} Hz)", keep=keep,
                 record=f"record length: {counted}")
    return [histories, spectra]
