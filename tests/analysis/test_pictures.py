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
