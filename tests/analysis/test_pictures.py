"""The pictures' annotations: modes named by what moves in them, labels kept apart."""
import pytest

from herringbone import load_scene
from herringbone.analysis.campbell import elastic_frequencies, elastic_modes
from herringbone.analysis.plots import spread_apart


def test_a_train_on_rigid_bearings_has_only_torsional_modes():
    modes = elastic_modes(load_scene("torsional"))
    assert len(modes) == 3
    assert all(mode.kind.startswith("torsional (") for mode in modes)


def test_reference_modes_are_named_by_their_dominant_motion():
    scene = load_scene("reference")
    modes = elastic_modes(scene)
    assert [m.frequency for m in modes] == list(elastic_frequencies(scene))
    named = {round(m.frequency, -1): (m.kind, m.bodies) for m in modes}
    # the motor against the load on the shafts; the mesh mode (the wheel turning against the
    # pinion); halves alike exert no moment about the line of centres, so the tilts move alone
    assert named[110.0] == ("torsional (100 % of kinetic energy)", ("load", "motor"))
    assert named[680.0] == ("torsional (98 % of kinetic energy)", ("wheel",))
    assert named[1500.0] == ("lateral (95 % of kinetic energy)", ("wheel",))
    assert named[2060.0] == ("tilt (100 % of kinetic energy)", ("wheel",))
    assert named[13350.0] == ("tilt (100 % of kinetic energy)", ("pinion",))
    # the pinion's lateral and torsional motions share these two modes
    assert named[4400.0][0] == "lateral (59 % of kinetic energy)"
    assert named[10420.0][0] == "torsional (56 % of kinetic energy)"


def test_the_campbell_diagram_names_each_mode_as_info_does():
    """`herringbone campbell reference` named the 10.4 kHz and 4397 Hz modes
    "torsional/lateral (pinion)" and "lateral/torsional (pinion)" where `herringbone info`
    says "torsional (56 % of kinetic energy)" and "lateral (59 % of kinetic energy)": the
    diagram now takes info's naming (report.mode_character), each label info's words for its
    mode and the bodies that move in it."""
    from herringbone.analysis.report import scene_report

    scene = load_scene("reference")
    lines = [line.split("Hz", 1) for line in scene_report(scene).splitlines()
             if line.rstrip().endswith("% of kinetic energy)")]
    info = {round(float(head.split()[-1]), 2): words.strip() for head, words in lines}
    modes = elastic_modes(scene)
    assert [info[round(m.frequency, 2)] for m in modes] == [m.kind for m in modes]
    assert modes[-2].label == "10419 Hz torsional (56 % of kinetic energy): pinion"
    assert modes[-3].label == "4397 Hz lateral (59 % of kinetic energy): pinion"


def test_labels_are_spread_at_least_a_gap_apart_and_under_the_ceiling():
    places = spread_apart([100.0, 110.0, 115.0, 900.0, 990.0], gap=50.0, ceiling=1000.0)
    assert all(b - a >= 50.0 - 1e-9 for a, b in zip(places, places[1:]))
    assert places[-1] <= 1000.0 and places[0] == 100.0
    assert spread_apart([1.0, 5.0], gap=1.0, ceiling=10.0) == [1.0, 5.0]


def test_a_spectrum_reaches_the_modes_its_sampling_resolves(monkeypatch, tmp_path):
    """Sampled at 10 µs (Nyquist 50 kHz), a run that rings at 10 kHz shows it: the frequency
    axis (logarithmic) runs past the highest natural frequency under Nyquist, where it stopped
    at 5.4 mesh harmonics (1350 Hz at 250 Hz) and hid every mode above; the harmonics marked
    stop at 12, which a log axis can still tell apart."""
    import matplotlib

    matplotlib.use("Agg")
    import numpy as np

    from herringbone.analysis import plots

    drawn = {}
    monkeypatch.setattr(plots, "_save", lambda figure, path, **kw: drawn.update(figure=figure))
    time = np.arange(0.0, 0.05, 1e-5)
    ringing = np.sin(2 * np.pi * 250.0 * time) + 0.1 * np.sin(2 * np.pi * 1.04e4 * time)
    results = {"time": time, "dte": 1e-6 * ringing, "F_mesh": 2e4 + 1e3 * ringing}
    plots.plot_spectra(results, tmp_path / "s.png", 250.0, [113.0, 684.0, 1.04e4, 1.34e4, 6e4],
                       "ringing", skip=0.025)
    axes = drawn["figure"].axes
    assert axes[1].get_xscale() == "log"
    low, high = axes[1].get_xlim()
    assert 1.34e4 < high <= 5e4  # the highest mode under Nyquist, not the one above it
    spectrum = axes[1].get_lines()[0]
    shown = spectrum.get_ydata()[np.abs(spectrum.get_xdata() - 1.04e4) < 100.0]
    assert 0.085 <= shown.max() <= 0.1  # the 100 N ringing at 10.4 kHz, in kN
    harmonics = [line for line in axes[0].get_lines() if line.get_color() == "C3"]
    assert len(harmonics) == plots.HARMONICS_MARKED


def test_a_spectrum_keeps_its_amplitude_axis_on_what_it_shows(monkeypatch, tmp_path):
    """Sampled at 1 µs, a tone of 250 Hz spans log frequency to 1350 Hz: the amplitude axis
    runs down to the least amplitude shown there (or SPECTRUM_DECADES under the peak), not to
    the leakage of the bins up to 500 kHz that the frequency axis leaves out, decades lower."""
    import matplotlib

    matplotlib.use("Agg")
    import numpy as np

    from herringbone.analysis import plots

    drawn = {}
    monkeypatch.setattr(plots, "_save", lambda figure, path, **kw: drawn.update(figure=figure))
    time = np.arange(0.0, 0.04, 1e-6)
    tone = np.sin(2 * np.pi * 250.0 * time)
    plots.plot_spectra({"time": time, "dte": 1e-6 * tone, "F_mesh": 2e4 + 1e3 * tone},
                       tmp_path / "s.png", 250.0, [113.0, 684.0], "tone", skip=0.02)
    for axes in drawn["figure"].axes[:2]:
        line = axes.get_lines()[0]
        frequency, amplitude = line.get_xdata(), line.get_ydata()
        left, right = axes.get_xlim()
        shown = amplitude[frequency <= right]
        low, high = axes.get_ylim()
        assert amplitude.min() < 1e-3 * shown.min()  # the leakage left out lies decades lower
        assert low == max(shown.min(), shown.max() * 10.0 ** -plots.SPECTRUM_DECADES)
        assert high > shown.max()


def test_a_parameter_sweeps_picture_names_its_speed_and_marks_contact_loss(monkeypatch,
                                                                          tmp_path):
    """`herringbone sweep reference --param dbeta_left 0 0.002 11 --speed 500`: the title
    held only "reference: K_v over dbeta_left", and nothing marked the 2 points where a helix
    half lost contact that the summary reported. Now the title gives the fixed speed (rad/s
    and rpm) and an open square marks each such point."""
    import matplotlib

    matplotlib.use("Agg")
    import numpy as np
    import pandas as pd

    from herringbone.analysis import sweep_plots, sweep_report

    drawn = {}
    monkeypatch.setattr(sweep_plots, "_save", lambda figure, path, **kw: drawn.update(
        figure=figure))
    values = np.linspace(0.0, 0.002, 11)
    table = pd.DataFrame({"dbeta_left": values, "speed_rpm": 500.0 * 30.0 / np.pi,
                          "K_v": 1.2 + 100.0 * values,
                          "contact_lost_share": [0.0] * 9 + [0.05, 0.2]})
    sweep_report.write_outputs(load_scene("reference"), table, None, tmp_path)
    axes = drawn["figure"].axes[0]
    assert axes.get_title() == "reference: K_v over dbeta_left at 500 rad/s (4775 rpm)"
    marked = [line for line in axes.get_lines() if line.get_label() == sweep_plots.CONTACT_LOST]
    assert len(marked) == 1 and list(marked[0].get_xdata()) == list(values[9:])
    assert sweep_plots.CONTACT_LOST in [text.get_text()
                                        for text in axes.get_legend().get_texts()]


def test_a_runs_spectrum_takes_whole_mesh_periods_at_its_end(monkeypatch, tmp_path):
    """`herringbone run reference --stop-time 0.02 --output-interval 1e-5 --plot`: the
    spectra took the second half, 10 ms = 2.5 mesh periods at 250 Hz, so the mesh line and
    its odd harmonics fell between bins. Now they take the last 2 whole periods (8 ms,
    800 samples, bins 125 Hz apart: every harmonic on one) and the annotation says so."""
    import matplotlib

    matplotlib.use("Agg")
    import numpy as np

    import herringbone
    from herringbone.analysis import plots, run_report

    drawn = []
    monkeypatch.setattr(plots, "_save", lambda figure, path, **kw: drawn.append(figure))
    scene = load_scene("reference")
    results = herringbone.simulate(scene, stop_time=0.02, output_interval=1e-5)
    run_report.plot_run(scene, results, tmp_path / "reference.csv")
    axes = drawn[-1].axes
    frequency = axes[0].get_lines()[0].get_xdata()  # from the first bin on
    mesh = scene.parameters["w0_pinion"] * scene.parameters["z_pinion"] / (2 * np.pi)
    spacing = frequency[1] - frequency[0]
    assert spacing == pytest.approx(mesh / 2, rel=1e-4)
    for k in range(1, 6):  # each harmonic within 1e-3 of a bin's spacing of a bin
        assert np.abs(frequency - k * mesh).min() <= 1e-3 * spacing, k
    assert "the last 2 mesh periods" in axes[0].get_title()
    assert any("record length: 2 mesh periods" in text.get_text() for text in axes[1].texts)
    keep, periods = plots.whole_mesh_periods(np.arange(0.0, 0.0025, 1e-5), 250.0)
    assert periods == 1 and keep.all()  # under a period in all: the whole run


def waterfall_drawn(monkeypatch, tmp_path, rpm, peaks, natural):
    """plot_waterfall's figure over synthetic points at `rpm`, each a window of 50 mesh
    periods at 64 samples a period (a sweep's) whose dte is 1 µm at the first mesh order plus
    the tones (Hz, µm) `peaks` gives at that speed; the reference scene's 10 pinion teeth."""
    import matplotlib

    matplotlib.use("Agg")
    import numpy as np
    import pandas as pd

    from herringbone.analysis import sweep_plots

    drawn = {}
    monkeypatch.setattr(sweep_plots, "_save", lambda figure, path, **kw: drawn.update(
        figure=figure, **kw))
    series = []
    for n in rpm:
        time = np.arange(50 * 64) * 60.0 / (10 * n) / 64
        dte = np.sin(2 * np.pi * 10 * n / 60 * time)
        for frequency, amplitude in peaks.get(n, ()):
            dte = dte + amplitude * np.sin(2 * np.pi * frequency * time)
        series.append({"time": time, "dte": 1e-6 * dte})
    table = pd.DataFrame({"speed_rpm": rpm, "w0_pinion": np.array(rpm) * np.pi / 30.0})
    sweep_plots.plot_waterfall(table, series, tmp_path / "w.png", natural, 10, "waterfall")
    return drawn


def test_a_waterfalls_near_peak_hides_the_rows_behind_it(monkeypatch, tmp_path):
    """`herringbone sweep reference --speeds 2000 9000 8 --rpm --method time`: the 4000 rpm
    row's 5.7 µm peak at 667 Hz rose through the 5000 rpm row's line up to the 6000 one, an
    unfilled line that read as ringing at 5000 rpm. Each trace is now filled beneath with the
    background and the lower rows drawn over the higher ones: at (667 Hz, 5000 rpm) the
    4000 rpm row's fill lies over the 5000 rpm row's line."""
    rpm = [4000.0, 5000.0, 6000.0]
    drawn = waterfall_drawn(monkeypatch, tmp_path, rpm, {4000.0: [(667.0, 5.7)]},
                            [684.0, 1497.0])
    axes = drawn["figure"].axes[0]
    fills = axes.collections[:3]
    traces = [line for line in axes.get_lines() if line.get_color() == "k"][:3]
    assert [fill.get_facecolor()[0][:3].tolist() for fill in fills] == [[1.0, 1.0, 1.0]] * 3
    assert fills[0].get_zorder() > traces[1].get_zorder() > fills[1].get_zorder() \
        > traces[2].get_zorder() > fills[2].get_zorder() > 1.0
    # the 4000 rpm peak, two rows tall, covers the 5000 rpm baseline beneath 667 Hz
    assert fills[0].get_paths()[0].contains_point((667.0, 5000.0))
    assert not fills[0].get_paths()[0].contains_point((2000.0, 5000.0))
    assert drawn["dpi"] == 200


def test_a_waterfalls_frequencies_reach_the_fastest_mode_the_samples_resolve(monkeypatch,
                                                                              tmp_path):
    """The frequency axis stopped at 1.15 × the third mesh order at the top speed, 5.2 kHz
    at 9000 rpm, and the reference scene's 10.4 and 13.4 kHz modes, where the mesh force
    rings most, never showed. It now runs to 1.1 × the fastest mode, 14.7 kHz, under the
    fastest trace's Nyquist frequency (48 kHz at 64 samples a mesh period); the 2000 rpm
    trace ends at its own, 10.7 kHz, and the axis label says why (bins 30 Hz apart at
    9000 rpm). Between 1000 and 2000 rpm the fastest trace ends at 10.7 kHz: the axis stops
    there and names the mode above it."""
    natural = [113.0, 684.0, 1497.0, 2059.0, 4397.0, 10418.6, 13354.5]
    drawn = waterfall_drawn(monkeypatch, tmp_path, [2000.0, 9000.0],
                            {9000.0: [(10500.0, 2.0)]}, natural)
    axes = drawn["figure"].axes[0]
    assert axes.get_xlim()[1] == pytest.approx(1.1 * 13354.5)
    ends = [line.get_xdata().max() for line in axes.get_lines() if line.get_color() == "k"]
    assert ends[:2] == [pytest.approx(10666.7, abs=0.1), pytest.approx(14690.0, abs=30.0)]
    dotted = [line.get_xdata()[0] for line in axes.get_lines() if line.get_linestyle() == ":"]
    assert dotted == natural
    assert "Nyquist frequency: 64 samples a mesh period, 32 mesh orders" in axes.get_xlabel()
    slow = waterfall_drawn(monkeypatch, tmp_path, [1000.0, 2000.0], {}, natural)
    axes = slow["figure"].axes[0]
    assert axes.get_xlim()[1] == pytest.approx(10666.7, abs=0.1)
    assert "modes at 13354 Hz above every trace's" in axes.get_xlabel()


def test_a_branchs_pictures_dot_every_orbit_computed(monkeypatch, tmp_path):
    """The beta sweep's curve (`herringbone sweep reference --param beta 0.35 0.6 6 --speed
    450`) drew a straight line from 0.3531 to 0.3765 that read as data; the time method's
    curves mark their points, the branch's did not. Each orbit now has a dot (markersize
    2.5) on its stretch, on the parameter curve and on both panels of the resonance curve,
    and the legend's entry shows the dot."""
    import matplotlib

    matplotlib.use("Agg")
    import numpy as np
    import pandas as pd

    from herringbone.analysis import sweep_plots

    drawn = []
    monkeypatch.setattr(sweep_plots, "_save", lambda figure, path, **kw: drawn.append(figure))
    beta = np.array([0.35, 0.3516, 0.3531, 0.3765, 0.40])
    table = pd.DataFrame({"beta": beta, "w0_pinion": 100.0 + 1000.0 * beta,
                          "speed_rpm": (100.0 + 1000.0 * beta) * 30 / np.pi,
                          "K_v": [2.27, 2.23, 2.17, 1.65, 1.77], "dte_p2p_um": 10.0,
                          "stability": ["stable"] * 3 + ["unstable"] * 2, "event": "",
                          "contact_lost_share": 0.0})
    sweep_plots.plot_parameter_sweep(table, ["beta"], tmp_path / "p.png", "beta")
    sweep_plots.plot_resonance_curve(table, tmp_path / "r.png", [], "speed")
    panels = [drawn[0].axes[0], *drawn[1].axes[:2]]
    for panel in panels:
        dotted = [line for line in panel.get_lines()
                  if str(line.get_label()).endswith("orbits") or line.get_marker() == "o"]
        assert dotted, [line.get_label() for line in panel.get_lines()]
        shown = np.concatenate([line.get_xdata()[np.isfinite(line.get_ydata())]
                                for line in dotted])
        assert {line.get_marker() for line in dotted} == {"o"}
        assert {line.get_markersize() for line in dotted} == {2.5}
        # every orbit dotted: the stable stretch's three, the unstable one's from the third
        along = beta if panel is panels[0] else table["speed_rpm"].to_numpy()
        assert np.allclose(np.unique(shown), along)
    legend = panels[0].get_legend()
    (entry,) = [handle for handle, text in zip(legend.legend_handles, legend.get_texts())
                if text.get_text() == "K_v, stable orbits"]
    assert entry.get_marker() == "o"


def drawn_run(monkeypatch, tmp_path, scene, results):
    """The figures run_report.plot_run draws for a run: (time histories, spectra); those
    drawn before closed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.close("all")
    from herringbone.analysis import plots, run_report

    drawn = []
    monkeypatch.setattr(plots, "_save", lambda figure, path, **kw: drawn.append(figure))
    run_report.plot_run(scene, results, tmp_path / "run.csv")
    return drawn


def amplitude_at(line, frequency):
    """A spectrum line's amplitude at the bin nearest `frequency` (Hz)."""
    import numpy as np

    return float(line.get_ydata()[np.argmin(np.abs(line.get_xdata() - frequency))])


def test_a_runs_spectrum_at_the_default_interval_reads_what_fine_samples_do(monkeypatch,
                                                                            tmp_path):
    """`herringbone run reference --stop-time 0.2 --plot`: the spectrum took the run's samples
    every 100 µs (Nyquist 5 kHz; the train rings at 10.4 and 13.4 kHz and the mesh force jumps
    at every contact switch): F_mesh read 773.9 N at 250 Hz and 1308.6 N at 2.5 kHz, against
    41.5 N and 18.1 N sampled every 1 µs. Its samples now come from the compiled integrator
    run again at 128 a period of the fastest mode (0.59 µs): within 5 % of those (40.8 N,
    17.6 N), and the title says where they come from and how often."""
    import numpy as np

    import herringbone
    from herringbone.analysis.plots import amplitude_spectrum, whole_mesh_periods

    scene = load_scene("reference")
    drawn = drawn_run(monkeypatch, tmp_path, scene, herringbone.simulate(scene, stop_time=0.2))
    fine = herringbone.simulate(scene, stop_time=0.2, output_interval=1e-6)
    keep, periods = whole_mesh_periods(fine["time"], 250.0)
    frequency, amplitude = amplitude_spectrum(fine["F_mesh"][keep], 1e-6)
    force = drawn[-1].axes[1].get_lines()[0]  # kN
    for harmonic in (250.0, 2500.0):
        truth = float(amplitude[np.argmin(np.abs(frequency - harmonic))])
        assert 1e3 * amplitude_at(force, harmonic) == pytest.approx(truth, rel=0.05), harmonic
    assert periods == 25
    title = drawn[-1].axes[0].get_title()
    assert "the last 25 mesh periods" in title and "f_mesh 250.0 Hz" in title
    assert "sampled every 0.592 µs by the compiled integrator run again" in title
    assert "every 100 µs, do not resolve it" in title
    assert drawn[-1].axes[1].get_xlim()[1] > 1.34e4  # the fastest modes show


def test_a_run_whose_speed_changes_marks_the_harmonics_of_its_window(monkeypatch, tmp_path):
    """docs/scenes.md's torque table (M_motor 500 then 1000 N·m from 10 ms; M_load 1800 N·m)
    speeds the pinion up from 157 rad/s to about 650: the spectrum said "f_mesh 250.0 Hz",
    the starting speed's, sized its window from it and marked its harmonics at 250, 500, 750
    Hz, and the time picture read "w0 1500 rpm". Now the mesh frequency is the mean pinion
    speed's over the window (818 Hz: 4910 rpm), the harmonics are bands over the speeds there
    (a line fitted to them: 607-1032 Hz), and the time picture gives the speed's range."""
    import math

    import numpy as np

    import herringbone

    scene = herringbone.scene_from_dict({
        "components": {"bearings": False}, "parameters": {"stagger": 0.5},
        "experiment": {"stop_time": 0.1, "output_interval": 1e-4},
        "inputs": {"table": [[0.0, 500.0, 1800.0], [0.01, 1000.0, 1800.0]]}}, name="table")
    drawn = drawn_run(monkeypatch, tmp_path, scene, herringbone.simulate(scene))
    histories, spectra = (figure.axes for figure in drawn)
    assert "(pinion 1508-59" in histories[0].get_title()
    assert "w0 1500 rpm" in histories[0].get_title()
    title = spectra[0].get_title()
    mesh = float(title.split("f_mesh ")[1].split(" Hz")[0])
    fine = herringbone.simulate(scene, output_interval=1e-6)
    window = fine["time"] >= 0.1 - 40.0 / mesh
    assert mesh == pytest.approx(np.mean(fine["w_pinion"][window]) * 10 / (2 * math.pi),
                                 rel=2e-3)
    assert mesh == pytest.approx(818.4, abs=1.0)
    assert "the last 40 mesh periods" in title
    bands = [patch.get_x() for patch in spectra[0].patches]
    widths = [patch.get_width() for patch in spectra[0].patches]
    assert bands[0] == pytest.approx(607.0, abs=5.0) and widths[0] == pytest.approx(425.0,
                                                                                      abs=10.0)
    assert bands[1] == pytest.approx(2 * bands[0])
    assert not [line for line in spectra[0].get_lines() if line.get_color() == "C3"]


def test_each_bodys_bearings_have_a_panel_and_a_style_a_side(monkeypatch, tmp_path):
    """`herringbone run lead_error --plot`: the four bearing traces shared one panel, a few
    percent apart and crossing at every mesh period, and could not be told apart. Each body's
    now has its own panel, left solid and right dashed in colours of their own, named in
    the legend; the reference scene's equal bearings are drawn once a body."""
    import herringbone

    scene = load_scene("lead_error")
    drawn = drawn_run(monkeypatch, tmp_path, scene, herringbone.simulate(scene, stop_time=0.02))
    axes = drawn[0].axes
    assert len(axes) == 4
    for panel, body in zip(axes[1:3], ("pinion", "wheel")):
        lines = panel.get_lines()
        assert [(line.get_color(), line.get_linestyle()) for line in lines] == [
            ("C0", "-"), ("C1", "--")]
        labels = [text.get_text() for text in panel.get_legend().get_texts()]
        assert [label.split(" (mean")[0] for label in labels] == [f"{body} left",
                                                                   f"{body} right"]
    scene = load_scene("reference")
    drawn = drawn_run(monkeypatch, tmp_path, scene, herringbone.simulate(scene, stop_time=0.02))
    assert [[text.get_text().split(" (mean")[0] for text in panel.get_legend().get_texts()]
            for panel in drawn[0].axes[1:3]] == [["pinion left = right"],
                                                 ["wheel left = right"]]


def drawn_sweep(monkeypatch):
    """The figures sweep_plots draws, laid out as _save lays them out; those drawn before
    closed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.close("all")
    from herringbone.analysis import sweep_plots

    drawn = []

    def save(figure, path, **kw):
        figure.tight_layout()
        figure.canvas.draw()
        drawn.append(figure)

    monkeypatch.setattr(sweep_plots, "_save", save)
    return drawn


def lead_error_branch():
    """A branch over the reference scene's speeds whose left half carries more of the load (a
    lead error): K_v_half up to 2.1 % over K_v, and a helix half out of contact at two
    orbits."""
    import numpy as np
    import pandas as pd

    speeds = np.array([100.0, 300.0, 470.0, 700.0, 1000.0])
    k_v = np.array([1.51, 1.47, 1.77, 1.50, 1.52])
    return pd.DataFrame({"w0_pinion": speeds, "speed_rpm": speeds * 30 / np.pi, "K_v": k_v,
                         "K_v_half": k_v * np.array([1.02, 1.021, 1.02, 1.02, 1.021]),
                         "dte_p2p_um": [13.6, 13.0, 21.7, 15.0, 14.2],
                         "contact_lost_share": [0.0, 0.0, 0.12, 0.03, 0.0],
                         "stability": "stable", "event": ""})


def test_a_lead_errors_sweep_draws_the_more_loaded_halfs_factor(monkeypatch, tmp_path):
    """`herringbone sweep lead_error --speeds 100 1000 12` printed "K_v_half ... 1.8087 ... the
    left half carries 51.7 %" but its pictures drew K_v alone, like the reference scene's.
    Where K_v_half exceeds K_v by more than HALF_FACTOR_SPREAD somewhere, the K_v panel draws
    it too (its own colour), on the resonance curve and the parameter curve, by shooting and
    by time integration; halves alike (K_v_half = K_v) draw none."""
    import numpy as np

    from herringbone.analysis import sweep_plots

    drawn = drawn_sweep(monkeypatch)
    branch = lead_error_branch()
    timed = branch.assign(stability="time").drop(columns="event").assign(dte_rms_um=3.0)
    sweep_plots.plot_resonance_curve(branch, tmp_path / "r.png", [], "branch")
    sweep_plots.plot_resonance_curve(timed.drop(columns="stability"), tmp_path / "t.png", [],
                                     "time")
    sweep_plots.plot_parameter_sweep(branch.assign(dbeta_left=np.linspace(0, 2e-4, 5)),
                                     ["dbeta_left"], tmp_path / "p.png", "parameter")
    for figure, label in zip(drawn, ["K_v_half (more loaded half), stable orbits",
                                     "K_v_half (more loaded half)",
                                     "K_v_half (more loaded half), stable orbits"]):
        (half,) = [line for line in figure.axes[0].get_lines() if line.get_label() == label]
        assert np.allclose(half.get_ydata(), branch["K_v_half"])
        assert half.get_color() == sweep_plots.HALF_COLOUR
        assert label in [text.get_text() for text in figure.axes[0].get_legend().get_texts()]
    from herringbone.analysis.sweep_plots import HALF_FACTOR_SPREAD

    assert HALF_FACTOR_SPREAD == 0.01
    alike = branch.assign(K_v_half=branch["K_v"] * 1.005)  # within HALF_FACTOR_SPREAD
    sweep_plots.plot_resonance_curve(alike, tmp_path / "a.png", [], "alike")
    assert not [line for line in drawn[-1].axes[0].get_lines()
                if str(line.get_label()).startswith("K_v_half")]


def test_a_speed_sweeps_resonance_curve_marks_contact_loss(monkeypatch, tmp_path):
    """`herringbone sweep jump_resonance --speeds 2300 2500 11` printed "a helix half out of
    contact at 58 points", and the parameter sweeps' pictures marked such points, but the
    resonance curve marked none. It now draws the same open square at each point with
    contact_lost_share > 0, on both panels."""
    from herringbone.analysis import sweep_plots

    drawn = drawn_sweep(monkeypatch)
    branch = lead_error_branch()
    sweep_plots.plot_resonance_curve(branch, tmp_path / "r.png", [], "branch")
    for panel, column in zip(drawn[0].axes[:2], ("K_v", "dte_p2p_um")):
        (marked,) = [line for line in panel.get_lines()
                     if line.get_label() == sweep_plots.CONTACT_LOST]
        assert list(marked.get_xdata()) == list(branch["speed_rpm"][2:4])
        assert list(marked.get_ydata()) == list(branch[column][2:4])
        assert marked.get_marker() == "s" and marked.get_markerfacecolor() == "none"
        # beneath the branch and its folds, which large red squares over them hid
        others = [line for line in panel.get_lines() if line is not marked and
                  line.get_label() and not line.get_label().startswith("_")]
        assert others and all(marked.get_zorder() < line.get_zorder() for line in others)
        assert marked.get_color() != "C3"  # the folds' colour


def test_resonance_labels_stand_apart_above_the_curve_joined_to_their_lines(monkeypatch,
                                                                             tmp_path):
    """`herringbone sweep reference --speeds 100 1000 12`: the labels of the resonances at
    4102 and 4119 rpm (684 and 2059 Hz) and at 8794 and 8984 rpm (4397 and 1497 Hz) stood at
    the foot of the K_v panel, across each other's lines and the K_v curve. They now stand
    above the panel, under the rad/s axis, none over another, each joined by a leader to the
    foot of its line at its speed."""
    import numpy as np
    from matplotlib.text import Text

    from herringbone.analysis import sweep_plots
    from herringbone.analysis.excitation import Resonance

    drawn = drawn_sweep(monkeypatch)
    natural = [112.9, 683.7, 1497.3, 2059.4, 4397.2, 10418.6, 13354.5]
    found = sorted((Resonance(2 * np.pi * f / (k * 10), k, f, 0.1, 0.05, 0.0) for f in natural
                    for k in (1, 2, 3) if 100.0 <= 2 * np.pi * f / (k * 10) <= 1000.0),
                   key=lambda r: r.speed)
    sweep_plots.plot_resonance_curve(lead_error_branch(), tmp_path / "r.png", found,
                                     "reference")
    figure = drawn[0]
    panel = figure.axes[0]
    renderer = figure.canvas.get_renderer()
    boxes = [Text.get_window_extent(text, renderer) for text in panel.texts]  # no leader
    resonances = [(r.speed, r.order, r.frequency) for r in found]
    assert len(boxes) == len(resonances) == 9
    top = panel.get_window_extent(renderer).y1
    assert min(box.y0 for box in boxes) > top  # above the panel, off the data
    ordered = sorted(boxes, key=lambda box: box.x0)
    assert all(b.x0 >= a.x1 for a, b in zip(ordered, ordered[1:]))  # none over another
    for text, (speed, _, frequency) in zip(panel.texts, resonances):
        assert text.get_text() == f" {frequency:.0f} Hz"
        assert text.xy == pytest.approx((speed * 30 / np.pi, 1.0))
        assert text.arrow_patch is not None
    axis = [child for child in panel.child_axes if child.get_xlabel()]
    assert axis[0].get_window_extent(renderer).y0 >= max(box.y1 for box in boxes)
