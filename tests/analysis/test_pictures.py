"""The pictures' annotations: modes named by what moves in them, labels kept apart."""
import pytest

from herringbone import load_scene
from herringbone.analysis.campbell import elastic_frequencies, elastic_modes
from herringbone.analysis.plots import spread_apart


def test_a_train_on_rigid_bearings_has_only_torsional_modes():
    modes = elastic_modes(load_scene("torsional"))
    assert len(modes) == 3
    assert all(mode.kind == "torsional" for mode in modes)


def test_reference_modes_are_named_by_their_dominant_motion():
    scene = load_scene("reference")
    modes = elastic_modes(scene)
    assert [m.frequency for m in modes] == list(elastic_frequencies(scene))
    named = {round(m.frequency, -1): (m.kind, m.bodies) for m in modes}
    # the motor against the load on the shafts; the mesh mode (the wheel turning against the
    # pinion); halves alike exert no moment about the line of centres, so the tilts move alone
    assert named[110.0] == ("torsional", ("load", "motor"))
    assert named[680.0] == ("torsional", ("wheel",))
    assert named[1500.0] == ("lateral", ("wheel",))
    assert named[2060.0] == ("tilt", ("wheel",))
    assert named[13350.0] == ("tilt", ("pinion",))
    # the pinion's lateral and torsional motions share these two modes
    assert {named[4400.0][0], named[10420.0][0]} == {"lateral/torsional", "torsional/lateral"}


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
    sweep_plots.plot_resonance_curve(table, tmp_path / "r.png", [], 10, "speed")
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
