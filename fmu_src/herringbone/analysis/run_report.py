"""What `herringbone run` writes and prints about a run: the CSV of its outputs (a header of
names with units), the summary table (with a unit column) and, with --plot, its pictures."""
from __future__ import annotations

import csv
import math
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..files import replace_file
from ..model.parameters import RPM_PER_RAD_S, name_with_unit, unit_of

# outputs shown in the summary in a unit more readable than SI: name -> (unit, factor)
SHOWN_IN = {"dte": ("µm", 1e6)}
# what a run does before its first step, as the summary says it
START_WORDS = "the model's tables, the compiled code loaded"


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
            start_time: float | None = None, start: str = START_WORDS,
            steps: int | None = None) -> str:
    """A few lines on a finished run: its span, the static mesh force, a table of each output
    (with its unit) at the start, its least and largest sample and at the end, and the time
    it took (`integrator`: what ran it, in words; `start_time`: the part of `wall_time`, s,
    before the stepping, None where it is not known; `start`: what that part did, in
    words; `steps`: the integrator's internal steps, where known)."""
    from ..model.assembly import GearTrainModel

    model = GearTrainModel(scene)
    stop = results["time"][-1]
    by = f" on {integrator}" if integrator else ""
    lines = [f"scene {scene.name} ({scene.source}): {model.size} degrees of freedom "
             f"({', '.join(model.coordinates)})",
             f"simulated {stop:g} s{by} in {_wall_time(stop, wall_time, start_time, start)}",
             *_steps_line(stop, steps),
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
    return [f"static mesh force M_motor/Rp = {static:.1f} N" + _torque_table_note(scene, model)
            + _back_flanks(static) + _tension_at_start(static, results["F_mesh"][0]),
            *_without_contact(model.mesh), *unbalance_lines(scene),
            *_large_deflection(scene.parameters["m_n"], results["dte"][0])]


def _torque_table_note(scene, model) -> str:
    """Where the scene's torque table changes M_motor: that the static mesh force is the first
    row's, and the force scale the tolerance is judged on (the largest torque's); '' else."""
    motor = scene.inputs.M_motor
    if min(motor) == max(motor):
        return ""
    return (f" at t = 0 (M_motor = {motor[0]:g} N·m, the torque table's first row; the "
            f"tolerance is relative to the largest torque's, {model.force_scale():.1f} N)")


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


def _wall_time(stop: float, wall_time: float, start_time: float | None,
               start: str = START_WORDS) -> str:
    """How long a run of `stop` simulated s took, in words: the start (`start` says what it
    did: a fixed cost that a short run's rate would hide the stepping under) apart from the
    stepping and its rate, where the start is known."""
    if start_time is None:
        return (f"{wall_time:.2f} s of wall time, start included "
                f"({wall_time / stop:.2f} s per simulated second)")
    stepping = wall_time - start_time
    return (f"{wall_time:.2f} s of wall time: {start_time:.2f} s to start ({start}), "
            f"{stepping:.3g} s stepping ({stepping / stop:.3g} s per simulated second)")


def _steps_line(stop: float, steps: int | None) -> list[str]:
    """How many internal steps a run of `stop` simulated s took, and their rate: what its
    cost grows with (an exact segment of the exponential method counts as one step)."""
    if steps is None:
        return []
    return [f"{steps} internal steps ({steps / stop:.3g} per simulated second)"]


# samples a period of the train's fastest mode (sweep_point.fastest_ringing) that a run's
# spectrum is taken from: far more than the mode needs, since the mesh force jumps at each
# contact switch of sharp face edges and point samples fold the jumps' broadband content onto
# every line, an error that falls as 1/samples. The reference scene's F_mesh over the last 25
# mesh periods of 0.2 s reads 41.2 N at 250 Hz and 18.0 N at 2.5 kHz sampled every 0.25 µs;
# at 128 (0.59 µs) 40.8 N and 17.6 N, at 64 39.4 N and 17.0 N, at the scene's 100 µs output
# interval 774 N and 1309 N
SPECTRUM_MODE_SAMPLES = 128
# the most samples of a spectrum that the compiled integrator is run again for (38 mesh periods
# of the reference scene): their rows of every output (22 there, 8 bytes each) take 46 MB
SPECTRUM_SAMPLES = 2**18
# a pinion speed whose mean varies by more than this share over a picture's samples changes:
# the time picture's title gives its range, the spectrum's harmonics smear (marked as bands)
SPEED_SPREAD = 0.03
# characters a line of a picture's title takes at most (10 pt over the 11 in figure's panels)
TITLE_WIDTH = 110


@dataclass(frozen=True)
class RunSpectrum:
    """What a run's spectrum picture shows: its samples and what they are."""
    samples: dict  # {"time": s, "dte": m, "F_mesh": N, "w_pinion": rad/s} over the window
    mesh_frequency: float  # Hz, of the mean pinion speed over the window
    mesh_band: tuple[float, float]  # Hz, the least and largest mesh frequency there (speed_line)
    periods: int  # mesh periods in the window (of mesh_frequency)
    fastest: float  # Hz, the train's fastest mode (sweep_point.fastest_ringing)
    run_interval: float  # s between the run's own samples
    run_again: bool  # the compiled integrator ran again for them: the run's were too coarse

    @property
    def interval(self) -> float:
        """s between the samples."""
        return float(np.diff(self.samples["time"]).mean())

    @property
    def smears(self) -> bool:
        """The mesh frequency varies by more than SPEED_SPREAD over the window."""
        low, high = self.mesh_band
        return self.mesh_frequency > 0.0 and high - low > SPEED_SPREAD * self.mesh_frequency


def speed_means(time, speed, span: float) -> np.ndarray:
    """The pinion's mean speed (rad/s, its magnitude) over each `span` s that ends at a sample
    (one mean over all the samples where they are shorter): the speed's trend, without its
    ripple at the mesh frequency or its ringing at the slowest mode, which a range of the raw
    samples reads as a change (the reference scene's pinion rings at 149-158 rad/s after its
    start about a steady 157.08 rad/s)."""
    time, speed = np.asarray(time, dtype=float), np.asarray(speed, dtype=float)
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(time))])
    span = min(span, float(time[-1] - time[0]))
    if span <= 0.0:
        return np.abs(speed[-1:])
    ends = time[time >= time[0] + span * (1.0 - 1e-9)]
    starts = np.maximum(ends - span, time[0])
    return np.abs(np.interp(ends, time, angle) - np.interp(starts, time, angle)) / span


def trend_span(natural, speed: float, z_pinion: int) -> float:
    """s that speed_means averages over: a period of the slowest mode (`natural`, Hz) or a
    mesh period at `speed` (rad/s), whichever is longer (0 where neither is known)."""
    periods = [1.0 / min(natural)] if len(natural) else []
    if speed > 0.0:
        periods.append(2.0 * math.pi / (speed * z_pinion))
    return max(periods, default=0.0)


def speed_words(scene, time, speed, span: float) -> str:
    """The pinion's speed in a title: the scene's "w0 1500 rpm", and where the pinion's mean
    speed over `span` s changes by more than SPEED_SPREAD of w0 (or of its own mean, where
    larger), its range first ("pinion 1500-4057 rpm, means over 8.86 ms; w0 1500 rpm"). Not
    the samples' mean: samples synchronous with the mesh period read the reference scene's
    steady 157.08 rad/s as 155.93 (every 100 µs), the fast ringing folded onto 0 Hz."""
    w0 = abs(scene.parameters["w0_pinion"]) * RPM_PER_RAD_S
    means = speed_means(time, speed, span) * RPM_PER_RAD_S
    words = f"w0 {w0:.0f} rpm"
    if means.max() - means.min() <= SPEED_SPREAD * max(w0, float(np.mean(means))):
        return words
    return (f"pinion {means.min():.0f}-{means.max():.0f} rpm, means over {1e3 * span:.3g} ms; "
            + words)


def spectrum_window(time, speed, z_pinion: int,
                    longest: float | None = None) -> tuple[np.ndarray, int, float]:
    """(which samples, how many mesh periods, the mesh frequency Hz): plots.whole_mesh_periods
    within `longest` s at the end (None: the second half) at the mesh frequency of the mean
    pinion speed (`speed`, rad/s) over the window, found in two passes (the mean over all
    that it may take sizes a window, whose own mean sizes it again); all it may take, 0
    periods and 0 Hz where the pinion does not turn."""
    from .plots import whole_mesh_periods

    time, speed = np.asarray(time, dtype=float), np.asarray(speed, dtype=float)
    span = 0.5 * (time[-1] - time[0]) if longest is None else longest
    keep = time >= time[-1] - span * (1.0 + 1e-9)
    periods, frequency = 0, 0.0
    for _ in range(2):
        frequency = abs(float(np.mean(speed[keep]))) * z_pinion / (2.0 * math.pi)
        if frequency * span <= 1e-9:  # no turn of the pinion: no mesh period
            return keep, 0, 0.0
        keep, periods = whole_mesh_periods(time, frequency, longest)
    return keep, periods, frequency


def finer_grid(window: float, period: float, wanted: float, stop: float) -> tuple[int, float]:
    """(samples, interval s) at the end of a run `stop` s long over `window` s and a mesh
    period more (`period`, s; 0 where the pinion stands), so that a window of a mean speed a
    little lower still fits, `wanted` s apart, at most SPECTRUM_SAMPLES of them: fewer
    periods where more would take more, and two periods (or the run where shorter) sampled
    coarser where they alone take more."""
    span = min(window + period, stop)
    if span <= SPECTRUM_SAMPLES * wanted:
        return math.ceil(span / wanted - 1e-9) + 1, wanted
    shortest = min(span, 2.0 * period) if period > 0.0 else span
    return SPECTRUM_SAMPLES, max(wanted, shortest / SPECTRUM_SAMPLES)


def finer_samples(scene, stop: float, count: int, interval: float,
                  tolerance: float | None) -> dict:
    """dte, F_mesh and w_pinion (m, N, rad/s) at `count` times `interval` s apart that end at
    `stop` (those from 0 on), from the compiled integrator run again from the start with the
    scene's torques (`tolerance`: its own, relative to the static mesh force; None: its
    default)."""
    from ..integrate.compiled_stepper import DEFAULT_TOLERANCE, CompiledStepper
    from ..integrate.contract import sampled_run
    from ..model.assembly import GearTrainModel

    times = stop - interval * np.arange(count)[::-1]
    times = times[times >= 0.0]
    times[-1] = stop
    stepper = CompiledStepper(GearTrainModel(scene),
                              DEFAULT_TOLERANCE if tolerance is None else tolerance)
    result = sampled_run(stepper, scene, stop, times)
    return {name: result[name] for name in ("time", "dte", "F_mesh", "w_pinion")}


def speed_line(time, speed) -> tuple[float, float]:
    """The least and largest (rad/s, magnitudes) of the straight line fitted to the pinion's
    speed over the samples, at their ends: the range a spectrum's harmonics smear over. A
    ramp's exactly; the ripple and the ringing about it, which a range of the samples reads
    as a change, average out."""
    time = np.asarray(time, dtype=float)
    if len(time) < 2 or time[-1] == time[0]:
        return abs(float(np.mean(speed))), abs(float(np.mean(speed)))
    slope, offset = np.polyfit(time - time[0], np.asarray(speed, dtype=float), 1)
    ends = np.abs([offset, offset + slope * (time[-1] - time[0])])
    return float(ends.min()), float(ends.max())


def run_spectrum(scene, results, tolerance: float | None = None) -> RunSpectrum:
    """The samples a run's spectra are taken from: the largest whole number of mesh periods
    (of the mean pinion speed there) in the second half of the run, at its end
    (spectrum_window), of the run's samples where they give the train's fastest mode
    (sweep_point.fastest_ringing) SPECTRUM_MODE_SAMPLES a period, else of the compiled
    integrator run again and sampled so over that window and a period more (finer_grid,
    finer_samples), the window found again in them (its mean speed from samples synchronous
    with the mesh period is off: speed_words). `tolerance`: the compiled integrator's,
    relative to the static mesh force (None: its default)."""
    from ..model.assembly import GearTrainModel
    from .sweep_point import fastest_ringing

    z, time = scene.parameters["z_pinion"], results["time"]
    keep, periods, frequency = spectrum_window(time, results["w_pinion"], z)
    fastest = fastest_ringing(GearTrainModel(scene))
    wanted = 1.0 / (SPECTRUM_MODE_SAMPLES * fastest)
    interval, stop = float(np.diff(time).mean()), float(time[-1])
    run_again = interval > wanted * (1.0 + 1e-9)
    samples = {name: results[name] for name in ("time", "dte", "F_mesh", "w_pinion")}
    if run_again:
        period = 1.0 / frequency if frequency > 0.0 else 0.0
        window = min(periods * period, keep.sum() * interval) if periods else stop / 2.0
        samples = finer_samples(scene, stop, *finer_grid(window, period, wanted, stop),
                                tolerance)
        record = samples["time"][-1] - samples["time"][0] + np.diff(samples["time"]).mean()
        keep, periods, frequency = spectrum_window(samples["time"], samples["w_pinion"], z,
                                                   min(record, 0.5 * (stop - time[0])))
    samples = {name: values[keep] for name, values in samples.items()}
    low, high = speed_line(samples["time"], samples["w_pinion"])
    hertz = z / (2.0 * math.pi)
    return RunSpectrum(samples, frequency, (low * hertz, high * hertz), periods, fastest,
                       interval, run_again)


def spectrum_title(scene, spectrum: RunSpectrum) -> str:
    """The spectrum picture's title: the window, the mesh frequency and the speed it is of;
    where the speed changes over the window, its range and the bands the harmonics smear
    over; the samples' interval and source (the run's, or the compiled integrator run again
    where the run's do not resolve the fastest mode), and how many a period of that mode."""
    f, (low, high), periods = spectrum.mesh_frequency, spectrum.mesh_band, spectrum.periods
    rpm_per_hz = 2.0 * math.pi / scene.parameters["z_pinion"] * RPM_PER_RAD_S
    record = len(spectrum.samples["time"]) * spectrum.interval
    if periods and record < 0.99 * periods / f:
        lines = [f"{scene.name}: amplitude spectra, the whole run, shorter than a mesh period "
                 f"(f_mesh {f:.3g} Hz, of the mean w_pinion: {f * rpm_per_hz:.3g} rpm)"]
    elif periods:
        lines = [f"{scene.name}: amplitude spectra, the last {periods} mesh "
                 f"period{'' if periods == 1 else 's'} of the run (f_mesh {f:.1f} Hz, of the "
                 f"mean w_pinion there: {f * rpm_per_hz:.0f} rpm)"]
    else:
        lines = [f"{scene.name}: amplitude spectra, the second half of the run (the pinion "
                 "does not turn: no mesh frequency)"]
    if spectrum.smears:
        lines.append(f"the pinion runs {low * rpm_per_hz:.0f}-{high * rpm_per_hz:.0f} rpm "
                     f"there: each harmonic smears over its shaded band, k·({low:.0f}-"
                     f"{high:.0f}) Hz")
    h, fastest = spectrum.interval, spectrum.fastest
    each = f"{1.0 / (h * fastest):.3g} a period of the fastest mode ({fastest:.0f} Hz)"
    if spectrum.run_again:
        lines.append(f"sampled every {h * 1e6:.3g} µs by the compiled integrator run again, "
                     f"{each}: the run's samples, every {spectrum.run_interval * 1e6:.3g} µs, "
                     "do not resolve it")
    else:
        lines.append(f"the run's samples, every {h * 1e6:.3g} µs, {each}")
    return "\n".join(textwrap.fill(line, TITLE_WIDTH) for line in lines)


def plot_run(scene, results, csv_path: Path, tolerance: float | None = None) -> list[Path]:
    """`run --plot`: time histories and amplitude spectra beside the run's CSV,
    <stem>_time.png and <stem>_spectrum.png; returns their paths. The time picture's title
    gives the pinion's speed (its range where it changes: speed_words); the spectra are of
    run_spectrum's samples (`tolerance`: the compiled integrator's where it runs again for
    them, relative to the static mesh force; None: its default)."""
    from .campbell import elastic_frequencies
    from .plots import plot_spectra, plot_time_histories

    stem = csv_path.with_suffix("")
    histories, spectra = Path(f"{stem}_time.png"), Path(f"{stem}_spectrum.png")
    natural, z = elastic_frequencies(scene), scene.parameters["z_pinion"]
    span = trend_span(natural, abs(scene.parameters["w0_pinion"]), z)
    words = speed_words(scene, results["time"], results["w_pinion"], span)
    plot_time_histories(results, histories, f"{scene.name}: time histories ({words})")
    spectrum = run_spectrum(scene, results, tolerance)
    periods = spectrum.periods
    plot_spectra(spectrum.samples, spectra, spectrum.mesh_frequency, natural,
                 spectrum_title(scene, spectrum), skip=-math.inf,
                 record=f"record length: {periods} mesh period{'' if periods == 1 else 's'}",
                 mesh_band=spectrum.mesh_band if spectrum.smears else None)
    return [histories, spectra]
