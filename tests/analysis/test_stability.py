"""Floquet stability of the linear mesh (herringbone.stability): the closed form of Meissner's
equation, Liouville, symplecticity, the quasi-static limit, convergence, and a simulation that
grows at the rate the largest multiplier predicts."""
import math

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
import scipy.optimize
from helpers import ROOT
from helpers.independent_model import bearing_positions, contact_points, contact_row, radii, unit

import herringbone
from herringbone.analysis import stability
from herringbone.model.assembly import GearTrainModel, natural_modes

# One mesh-like degree of freedom: the equivalent mass of the reference pair and a stiffness that
# alternates between six and four points for 30 % and 70 % of the period.
MASS, STIFF, SOFT, STIFF_SHARE = 0.43, 1.5e9, 1.0e9, 0.3
DAMPING = 2 * 0.02 * math.sqrt((STIFF_SHARE * STIFF + (1 - STIFF_SHARE) * SOFT) * MASS)


def meissner_machinery(periods):
    """The multipliers of Meissner's equation through the gear's own integration path."""
    stretches = [stability.Stretch.constant(STIFF, DAMPING),
                 stability.Stretch.constant(SOFT, DAMPING)]
    durations = np.column_stack([STIFF_SHARE * periods, (1 - STIFF_SHARE) * periods])
    return np.linalg.eigvals(stability.periodic_monodromy(MASS, stretches, durations))


def meissner_closed_form(period):
    return stability.meissner_multipliers(STIFF, SOFT, MASS, DAMPING, STIFF_SHARE * period,
                                          (1 - STIFF_SHARE) * period)


def test_meissner_multipliers_and_band_edges_match_the_closed_form():
    """Over the first two instability bands (mesh frequency 2·ω_n and ω_n), with damping."""
    natural = math.sqrt((STIFF_SHARE * STIFF + (1 - STIFF_SHARE) * SOFT) / MASS)
    periods = np.linspace(0.5, 2.5, 801) * math.pi / natural
    machinery = meissner_machinery(periods)
    machinery = np.take_along_axis(machinery, np.argsort(-np.abs(machinery), axis=1), axis=1)
    closed = np.array([meissner_closed_form(t) for t in periods])
    error = np.abs(machinery - closed).max(axis=1) / np.abs(closed[:, 0])
    assert error.max() < 1e-8
    assert np.prod(machinery, axis=1).real == pytest.approx(np.exp(-DAMPING * periods / MASS),
                                                            rel=1e-10, abs=0)

    largest = np.abs(machinery[:, 0])
    bands = stability.unstable_bands(periods, largest)
    principal, second = [b for b in bands if b[0] < math.pi / natural < b[1]], \
        [b for b in bands if b[0] < 2 * math.pi / natural < b[1]]
    assert len(principal) == 1 and len(second) == 1
    assert largest.max() > 1.1  # a real band, not a graze of |λ| = 1

    def machinery_excess(t):
        return np.abs(meissner_machinery(np.array([t]))).max() - 1.0

    def closed_excess(t):  # the Jury condition |tr/2| < (1 + det)/2 in closed form
        half_trace = stability.meissner_half_trace(STIFF, SOFT, MASS, DAMPING,
                                                   STIFF_SHARE * t, (1 - STIFF_SHARE) * t)
        return abs(half_trace) - 0.5 * (1 + math.exp(-DAMPING * t / MASS))

    spacing = periods[1] - periods[0]
    for band in principal + second:
        for edge in band:
            bracket = (edge - spacing, edge + spacing)
            expected = scipy.optimize.brentq(closed_excess, *bracket, xtol=1e-16, rtol=1e-14)
            found = scipy.optimize.brentq(machinery_excess, *bracket, xtol=1e-16, rtol=1e-14)
            assert found == pytest.approx(expected, rel=1e-10, abs=0)
            # the sampled sweep's linear interpolation
            assert edge == pytest.approx(expected, rel=1e-3, abs=0)


def test_closed_form_transition_covers_every_damping():
    """Under-, critically and over-damped segments against the matrix exponential."""
    for damping in (0.3, 2.0, 7.0):  # k = 1, m = 1: critical at c = 2
        expected = scipy.linalg.expm(np.array([[0.0, 1.0], [-1.0, -damping]]) * 0.7)
        found = stability.constant_stiffness_transition(1.0, 1.0, damping, 0.7)
        assert found == pytest.approx(expected, rel=1e-12, abs=1e-14)


# --- the gear train --------------------------------------------------------------------------

def mesh_damping_factor(p):
    """η = 2·ζ_mesh/ω_m of docs/model.md section 3, written out again."""
    rp, rw = radii(p)
    p_x = math.pi * p["m_n"] / math.sin(p["beta"])
    mean_stiffness = p["c_point"] * 2 * (p["b_left"] + p["b_right"]) / p_x
    equivalent_mass = 1 / (rp ** 2 / p["I_pinion"] + rw ** 2 / p["I_wheel"])
    return 2 * p["zeta_mesh"] / math.sqrt(mean_stiffness / equivalent_mass)


def independent_damping_matrix(p, pinion_angle):
    """C of docs/model.md sections 3-4 at a pinion angle, over the 8 coordinates, by hand."""
    zeta_left, zeta_right = bearing_positions(p)
    rows = [(unit(0) - unit(1), p["h_shaft_in"]), (unit(4) - unit(7), p["h_shaft_out"])]
    for gear, x, psi in (("pinion", 3, 2), ("wheel", 6, 5)):
        rows.append((unit(x) + zeta_left * unit(psi), p[f"h_brg_{gear}_left"]))
        rows.append((unit(x) + zeta_right * unit(psi), p[f"h_brg_{gear}_right"]))
    eta = mesh_damping_factor(p)
    rows += [(contact_row(p, zeta), eta * p["c_point"])
             for _, _, zeta in contact_points(p, pinion_angle)]
    return sum(h * np.outer(g, g) for g, h in rows)


def test_damping_matrix_matches_model_md(reference_scene):
    model = GearTrainModel(reference_scene)
    for angle in (0.0, 0.03, 0.1, 0.4):
        contact_set = model.mesh.contact_set(*model.mesh.locate(angle))
        y = np.zeros(model.size)
        y[model.pinion] = angle - contact_set.pinion_angle
        expected = independent_damping_matrix(reference_scene.parameters, angle)
        assert model.damping_matrix(y, contact_set) == pytest.approx(
            expected, rel=1e-10, abs=1e-12 * np.abs(expected).max())


def test_determinant_follows_liouville(reference_scene):
    """det Φ = exp(−∫ trace(M⁻¹·C) dt) over the period, the trace integrated by hand."""
    p = reference_scene.parameters
    inverse_mass = 1 / GearTrainModel(reference_scene).mass
    pitch = 2 * math.pi / p["z_pinion"]
    switches = GearTrainModel(reference_scene).mesh.switch_phases * pitch
    trace_integral, _ = scipy.integrate.quad(
        lambda angle: np.trace(inverse_mass[:, None] * independent_damping_matrix(p, angle)),
        0.0, pitch, points=switches[1:], epsabs=0, epsrel=1e-13, limit=200)
    # (slower, the fast modes decay so far within a period that det Φ, 1e-40 at 300 rad/s, is
    # itself computed only to ~1e-8)
    for speed in (1000.0, 5000.0):
        determinant = np.linalg.det(stability.monodromy(reference_scene, speed))
        assert determinant == pytest.approx(math.exp(-trace_integral / speed), rel=1e-9, abs=0)


UNDAMPED = dict(zeta_mesh=0.0, h_shaft_in=0.0, h_shaft_out=0.0,
                **{f"h_brg_{g}_{s}": 0.0 for g in ("pinion", "wheel") for s in ("left", "right")})


@pytest.mark.parametrize("speed", [157.08, 2000.0])
def test_undamped_monodromy_is_symplectic(reference_scene, speed):
    """Without damping the rigid-free system is Hamiltonian (mass I): Φᵀ·J·Φ = J, det Φ = 1
    and the multipliers come in pairs λ, 1/λ."""
    phi = stability.monodromy(reference_scene.with_parameters(**UNDAMPED), speed)
    n = len(phi) // 2
    j = np.block([[np.zeros((n, n)), np.eye(n)], [-np.eye(n), np.zeros((n, n))]])
    assert phi.T @ j @ phi == pytest.approx(j, abs=1e-9 * np.abs(phi).max() ** 2)
    assert np.linalg.det(phi) == pytest.approx(1.0, rel=1e-9)
    moduli = np.sort(np.abs(np.linalg.eigvals(phi)))
    assert moduli * moduli[::-1] == pytest.approx(np.ones(2 * n), rel=1e-10)


def reference_monodromy(scene, speed):
    """Φ by scipy's DOP853 at 1e-12 on the matrix ODE, interval by interval: no Magnus steps."""
    model = GearTrainModel(scene)
    basis = stability.rigid_free_basis(model)
    n = model.size - 1
    phi = np.eye(2 * n)
    for interval in range(len(model.mesh.switch_phases)):
        contact_set = model.mesh.contact_set(0, interval)

        def derivative(t, flat, contact_set=contact_set):
            y = np.zeros(model.size)
            y[model.pinion] = speed * t
            a = np.zeros((2 * n, 2 * n))
            a[:n, n:] = np.eye(n)
            a[n:, :n] = -basis.T @ model.stiffness_matrix(y, contact_set) @ basis
            a[n:, n:] = -basis.T @ model.damping_matrix(y, contact_set) @ basis
            return (a @ flat.reshape(2 * n, 2 * n)).ravel()

        solution = scipy.integrate.solve_ivp(derivative, (0, contact_set.length / speed),
                                             phi.ravel(), method="DOP853", rtol=1e-12,
                                             atol=1e-14)
        phi = solution.y[:, -1].reshape(2 * n, 2 * n)
    return phi


def test_magnus_steps_converge_to_the_ode_solution(reference_scene):
    """The lever arms move within an interval, so the steps matter; fourth order in the step."""
    speed = 1000.0
    expected = reference_monodromy(reference_scene, speed)
    errors = [np.abs(stability.monodromy(reference_scene, speed, step_phase=phase) - expected)
              .max() / np.abs(expected).max() for phase in (2.0, 1.0, 0.5)]
    assert errors[1] < 2e-6  # the default step
    assert errors[0] / errors[1] > 8 and errors[1] / errors[2] > 8
    found = stability.multipliers(reference_scene, speed)
    values = np.linalg.eigvals(expected)
    assert all(np.abs(values - f).min() < 1e-6 * np.abs(values).max() for f in found)


def test_the_interpolated_stretches_reproduce_the_model_with_an_edge_ramp(reference_scene):
    """K and C are cubic in the travel (point stiffness and lever arm linear in it)."""
    model = GearTrainModel(reference_scene.with_parameters(edge_ramp=0.004, zeta_mesh=0.1))
    basis = stability.rigid_free_basis(model)
    stretches, lengths = stability.mesh_stretches(model)
    for interval, stretch in enumerate(stretches):
        contact_set = model.mesh.contact_set(0, interval)
        for fraction in (0.17, 0.71):
            y = np.zeros(model.size)
            y[model.pinion] = fraction * lengths[interval]
            a = stretch.state_matrices(np.array(fraction), np.eye(model.size - 1))
            n = model.size - 1
            stiffness = basis.T @ model.stiffness_matrix(y, contact_set) @ basis
            damping = basis.T @ model.damping_matrix(y, contact_set) @ basis
            assert -a[n:, :n] == pytest.approx(stiffness, rel=1e-9, abs=1e-9 * abs(stiffness).max())
            assert -a[n:, n:] == pytest.approx(damping, rel=1e-9, abs=1e-9 * abs(damping).max())


def test_constant_mesh_stiffness_gives_the_multipliers_of_the_modes(torsional_scene):
    """Faces of exactly one axial pitch hold one point per stream at all times: on rigid bearings
    K is then constant and the multipliers are e^(s·T) of the modes, at any speed."""
    p = torsional_scene.parameters
    pitch = math.pi * p["m_n"] / math.sin(p["beta"])
    scene = torsional_scene.with_parameters(b_left=pitch, b_right=pitch)
    model = GearTrainModel(scene)
    basis = stability.rigid_free_basis(model)
    contact_set = model.mesh.contact_set(0, 0)
    stiffness = basis.T @ model.stiffness_matrix(np.zeros(model.size), contact_set) @ basis
    damping = basis.T @ model.damping_matrix(np.zeros(model.size), contact_set) @ basis
    n = model.size - 1
    state = np.block([[np.zeros((n, n)), np.eye(n)], [-stiffness, -damping]])
    exponents = np.linalg.eigvals(state)
    for speed in (30.0, 3000.0):
        period = 2 * math.pi / p["z_pinion"] / speed
        expected = np.exp(exponents * period)
        found = stability.multipliers(scene, speed)
        assert all(np.abs(found - e).min() < 1e-10 * np.abs(expected).max() for e in expected)


def test_quasi_static_exponents_are_the_period_mean_of_the_frozen_ones(reference_scene):
    """Slowly turning, each mode follows its frozen frequency and damping: ln|λ|/T tends to the
    period mean of Re s(φp) of the frozen state matrices (for the four slowest-decaying modes:
    eight exponents in conjugate pairs; at 30 rad/s within 1e-4, at 300 within 1e-3)."""
    model = GearTrainModel(reference_scene)
    stretches, lengths = stability.mesh_stretches(model)
    fractions = (np.arange(400) + 0.5) / 400
    mean = sum(length * np.sort(np.linalg.eigvals(stretch.state_matrices(
        fractions, np.eye(model.size - 1))).real, axis=1)[:, ::-1].mean(axis=0)
        for stretch, length in zip(stretches, lengths)) / lengths.sum()
    errors = []
    for speed in (300.0, 30.0):
        period = lengths.sum() / speed
        exponents = np.log(np.abs(stability.multipliers(reference_scene, speed))) / period
        errors.append(np.abs(exponents[:8] / mean[:8] - 1).max())
    assert errors[1] < 2e-4 and errors[1] < errors[0] / 5


# --- bands, and a simulation inside one --------------------------------------------------------

@pytest.fixture(scope="module")
def resonance_scene(torsional_scene):
    """The reference gear on rigid bearings made to resonate parametrically:
    - light damping: ζ_mesh 0.005 and shafts of 0.02 N·m·s/rad (the reference 1.0 N·m·s/rad on
      the small pinion inertia alone damps the 8.3 kHz mesh mode at about 2100 1/s);
    - contact_loss false: the linear mesh the Floquet analysis describes;
    - 2080 rad/s (19 900 rpm): five mesh periods hold two and a half periods of the mesh mode
      (f_mesh = 2f/5), where the largest multiplier is −1.327, a growth of 937 1/s. The mesh
      stiffness alternates as a pulse train rich in harmonics, so this band outgrows (per second)
      all but the principal one (f_mesh = 2f, near 10 400 rad/s, more switches to simulate);
    - small torques: the train is linear, so every vibration the start excites scales with them,
      and they keep the growing vibration small against the speed through the run."""
    return torsional_scene.with_parameters(
        contact_loss=False, zeta_mesh=0.005, h_shaft_in=0.02, h_shaft_out=0.02,
        w0_pinion=2080.0).with_inputs(M_motor=0.01, M_load=0.036)


def test_chart_finds_the_bands_where_the_mesh_mode_resonates(resonance_scene, torsional_scene,
                                                            reference_scene, tmp_path):
    """Bands at mesh frequencies 2f/k of the 8.3 kHz mesh mode, none at the reference damping."""
    z = resonance_scene.parameters["z_pinion"]
    mesh_mode = natural_modes(resonance_scene)[0][-1]
    speeds = np.linspace(1000.0, 12000.0, 551)
    chart = stability.stability_chart(resonance_scene, speeds)
    for order in (1, 2, 5):
        predicted = 2 * mesh_mode / order * 2 * math.pi / z
        assert any(low < predicted < high for low, high in chart.unstable_bands), order
    assert all((chart.largest_modulus > 1 + chart.resolution)
               == [any(lo <= s <= hi for lo, hi in chart.unstable_bands) for s in speeds])
    # between bands, and for the reference damping everywhere: every multiplier inside the circle
    assert np.abs(stability.multipliers(resonance_scene, 8000.0)).max() < 1.0
    damped = torsional_scene.with_parameters(contact_loss=False)
    assert stability.stability_chart(damped, speeds).unstable_bands == ()
    assert np.abs(stability.multipliers(reference_scene, 157.08)).max() < 1.0
    path = tmp_path / "chart.png"
    stability.plot_stability_chart(chart, path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_simulation_grows_at_the_rate_of_the_largest_multiplier(resonance_scene):
    """The reference integration inside the band: the peaks of |F_mesh − static| per mesh period
    grow like |λ|max^(t/T), once the growing solution outweighs the start's transient."""
    speed = resonance_scene.parameters["w0_pinion"]
    period = 2 * math.pi / resonance_scene.parameters["z_pinion"] / speed
    predicted = math.log(stability.largest_multiplier(resonance_scene, speed)) / period
    results = herringbone.reference_simulate(resonance_scene, stop_time=0.012,
                                             output_interval=2e-6)
    static = resonance_scene.inputs.M_motor[0] / radii(resonance_scene.parameters)[0]
    time, deviation = results["time"], np.abs(results["F_mesh"] - static)
    # from 4 ms on, the growing solution has outgrown the start's transient (e^(937·0.004) = 42)
    starts = np.arange(0.004, time[-1] - period, period)
    peaks = np.array([deviation[(time >= t) & (time < t + period)].max() for t in starts])
    measured = np.polyfit(starts, np.log(peaks), 1)[0]
    assert measured == pytest.approx(predicted, rel=0.01)  # measured 936.6 1/s, predicted 937.1
    # the pinion's share of the growing vibration stays small against its speed
    assert np.abs(results["w_pinion"] - speed).max() < 0.02 * speed


def test_command_line_lists_the_bands_of_the_example(tmp_path, capsys):
    """`herringbone stability` on the shipped example: the k = 5 band around 2080 rad/s is
    found, and the chart is written."""

    from herringbone.cli import main

    example = ROOT / "examples" / "parametric_resonance.toml"
    chart = tmp_path / "chart.png"
    assert main(["stability", str(example), "--speeds", "1900", "2300", "81",
                 "-o", str(chart)]) == 0
    printed = capsys.readouterr().out
    bands = [line for line in printed.splitlines() if line.startswith("unstable:")]
    assert len(bands) == 1
    low, high = (float(x) for x in bands[0].split()[1].split("-"))
    assert low < 2080.0 < high and chart.stat().st_size > 10_000


def test_band_edges_are_bisected_to_their_tolerance_whatever_the_grid(resonance_scene):
    """The k = 5 band of the example charted on 100 speeds over 1000-12000 rad/s (111 rad/s
    apart) and on 81 over 1900-2300 (5 rad/s apart): its edges, bisected between the grid
    points, agree within the tolerance (0.01 rad/s; 2034.18-2128.96 rad/s on both, where the
    lines between the grid points gave 2000.0-2222.2 and 2030.0-2130.0, each on the stable
    neighbour), |λ|max is inside the circle a tolerance outside each edge and outside it a
    tolerance inside, the command's line prints them to the hundredth, and the chart's curve
    passes 0 at them."""
    from herringbone.cli.stability import summary

    coarse = stability.stability_chart(resonance_scene, np.linspace(1000.0, 12000.0, 100))
    fine = stability.stability_chart(resonance_scene, np.linspace(1900.0, 2300.0, 81))
    tolerance = 0.01
    (band,) = [b for b in coarse.unstable_bands if b[0] < 2080.0 < b[1]]
    (fine_band,) = fine.unstable_bands
    assert band == pytest.approx(fine_band, abs=tolerance)
    assert band == pytest.approx((2034.18, 2128.96), abs=tolerance)
    assert fine.edge_tolerance == coarse.edge_tolerance == tolerance
    low, high = band
    excess = stability.largest_multiplier(
        resonance_scene, np.array([low - tolerance, low + tolerance, high - tolerance,
                                   high + tolerance])) - 1.0
    assert list(excess > 0) == [False, True, True, False], excess
    printed = [line for line in summary(fine) if line.startswith("unstable:")]
    assert printed[0].startswith(f"unstable: {fine_band[0]:.2f}-{fine_band[1]:.2f} rad/s")
    assert "edges to ±0.005 rad/s" in printed[0]
    # the chart's curve crosses 0 at the edges it shades, between its charted speeds
    speeds, exponent = stability.chart_curve(coarse)
    assert len(speeds) == (len(coarse.speeds) + len(coarse.probed_speeds)
                           + 2 * len(coarse.unstable_bands))
    assert list(exponent[np.isin(speeds, band)]) == [0.0, 0.0]


def test_a_coarse_chart_probes_where_bands_hide_or_merge():
    """`herringbone stability parametric_resonance --speeds 1000 12000 100` (111 rad/s apart)
    gave 1711.13-1889.05 rad/s as one band over two stable gaps, and had no band at 1040-1083,
    1118-1141 or 1394-1435 rad/s (|λ|max up to 1.010), which fall between its speeds. It now
    probes each interval beside an unstable speed or a near-unstable peak at 7 speeds more
    (13.9 rad/s apart) and the midpoint of each two unstable ones: over 1000-3000 rad/s it
    gives the bands of a chart 1 rad/s apart but one of 8.7 rad/s (2839.96-2848.64, narrower
    than the probes' spacing), at 337 monodromies besides its 100; the summary says which
    widths its spacing can miss."""
    from herringbone.cli.stability import summary

    scene = herringbone.load_scene(ROOT / "examples" / "parametric_resonance.toml")
    coarse = stability.stability_chart(scene, np.linspace(1000.0, 12000.0, 100))
    fine = stability.stability_chart(scene, np.arange(1000.0, 3000.5, 1.0))
    spacing = coarse.grid_step / coarse.refine_split
    assert spacing == pytest.approx(13.89, abs=0.01)
    found = [band for band in coarse.unstable_bands if band[1] < 3000.0]
    missed = [band for band in fine.unstable_bands if band not in found]
    (thin,) = [band for band in fine.unstable_bands if 2800.0 < band[0] < 3000.0]
    assert thin == pytest.approx((2839.96, 2848.64), abs=0.01) and thin[1] - thin[0] < spacing
    others = [band for band in fine.unstable_bands if band != thin]
    assert len(found) == len(others) == 10
    assert np.allclose(found, others, atol=0.02), missed
    assert np.allclose(found[4:7], [(1711.13, 1753.09), (1759.60, 1779.56), (1879.00, 1889.05)],
                       atol=0.01)
    assert len(coarse.probed_speeds) == 337
    assert stability.largest_multiplier(scene, 1732.5) == pytest.approx(1.159, abs=1e-3)
    lines = summary(coarse)
    assert "probed 337 speeds besides the 100 charted (a monodromy each)" in lines[-2]
    assert lines[-1] == ("a band, or a stable gap between two, narrower than the grid step, "
                         "111 rad/s (13.9 rad/s where the chart probed), may be missed or "
                         "merged: give more speeds to see finer")


@pytest.fixture(scope="module")
def undamped_chart():
    """models/undamped.toml charted over 100-2000 rad/s in 20 speeds: parametric resonance at
    100 and 1100 rad/s (|λ|max 1.005 and 1.0025), every other charted multiplier on the unit
    circle; four thin bands more between the charted speeds, probed beside the unstable ones
    (an undamped train has bands wherever a combination of its modes meets a mesh order)."""
    return stability.stability_chart(undamped_train(), np.linspace(100.0, 2000.0, 20))


def undamped_train():
    """models/undamped.toml."""
    return herringbone.load_scene(ROOT / "models" / "undamped.toml")


def test_an_undamped_train_is_neutral_where_its_exponent_is_rounding(undamped_chart):
    """Without damping |λ|max is 1 but for rounding (1 + 4e-16 to 1 + 1e-14, an exponent of
    6e-13 to 7e-12 1/s) away from the bands: neutral, no band, within the resolution the chart
    derives (which bounds the rounding tenfold over); the two real bands are still found."""
    chart = undamped_chart
    growing = np.isin(chart.speeds, [100.0, 1100.0])
    assert np.all(chart.largest_modulus[growing] - 1 > 1e-3)
    assert np.array_equal(chart.neutral, ~growing)
    rounding = np.abs(chart.largest_modulus[~growing] - 1.0)
    assert rounding.max() > 0 and np.all(rounding < chart.resolution[~growing] / 10)
    assert np.all(chart.resolution < 1e-10)  # far below any band worth the name
    assert np.all(np.abs(chart.largest_exponent[~growing]) <= chart.exponent_resolution[~growing])
    for speed in (100.0, 1100.0):
        (low, high), = [(a, b) for a, b in chart.unstable_bands if a <= speed <= b]
        assert high - low <= 200.0  # no wider than its neighbours
    assert not any(low <= s <= high for low, high in chart.unstable_bands
                   for s in chart.speeds[~growing])
    # the bands probed between the charted speeds grow inside their edges and not outside
    assert len(chart.unstable_bands) == 6
    for low, high in chart.unstable_bands[1:]:
        excess = stability.largest_multiplier(
            undamped_train(), np.array([low - 0.01, low + 0.01, high - 0.01, high + 0.01])) - 1.0
        assert np.all(excess[[1, 2]] > 1e-3) and np.all(np.abs(excess[[0, 3]]) < 1e-10)


def test_the_summary_of_an_undamped_train_says_nothing_decays(undamped_chart, tmp_path,
                                                              capsys):
    """The command's words agree with its chart: no "every disturbance decays" where nothing
    does, the neutral speeds said so, and only the real bands listed."""
    from herringbone.cli import main
    from herringbone.cli.stability import summary

    lines = summary(undamped_chart)
    assert not any("decays" in line and "every" in line for line in lines), lines
    assert any("neither grows nor decays" in line and "18 of 20" in line for line in lines)
    assert len([line for line in lines if line.startswith("unstable:")]) == 6
    assert main(["stability", "undamped", "--speeds", "200", "1000", "9", "--no-progress",
                 "-o", str(tmp_path / "chart.png")]) == 0
    printed = capsys.readouterr().out
    assert "unstable:" not in printed and "every disturbance decays" not in printed
    assert "no unstable band" in printed and "9 of 9 speeds" in printed


def test_chart_reads_as_a_decay_rate_that_does_not_creep_towards_instability(reference_scene):
    """The chart's exponent ln|λ|max/T (1/s): on the reference scene, stable at every speed,
    it stays near −σ of the least-damped mode (the 113 Hz motor-load mode, σ ≈ 2 1/s: within
    a third of it) while |λ|max per period creeps from 0.987 to 0.9996; the chart in batches
    with its progress reported gives the same numbers."""
    from herringbone.analysis.sweep_point import least_damped_decay_rate

    speeds = np.linspace(100.0, 3000.0, 30)
    chart = stability.stability_chart(reference_scene, speeds)
    sigma = least_damped_decay_rate(reference_scene)
    assert chart.largest_modulus[0] < 0.99 < 0.999 < chart.largest_modulus[-1] < 1.0
    assert np.all(np.abs(chart.largest_exponent + sigma) < sigma / 3)
    period = 2 * math.pi / (10 * speeds)
    assert np.allclose(chart.largest_exponent, np.log(chart.largest_modulus) / period,
                       rtol=1e-12)
    assert not chart.neutral.any()
    from herringbone.cli.stability import summary

    assert "below zero at every speed: every disturbance decays" in summary(chart)
    done = []
    grouped = stability.stability_chart(reference_scene, speeds, on_progress=done.append)
    assert sum(done) == len(speeds) and len(done) > 1
    assert np.allclose(grouped.largest_modulus, chart.largest_modulus, rtol=1e-13, atol=0)


def test_the_charts_legend_stands_beside_the_plot_off_its_curve(undamped_chart, monkeypatch,
                                                                tmp_path):
    """An undamped train's chart has bands all over its speeds and peaks up to its top: the
    legend stands to the right of the axes, where it covers none of them."""
    from herringbone.analysis import plots

    drawn = {}
    monkeypatch.setattr(plots, "_save", lambda figure, path, **kw: drawn.update(figure=figure))
    stability.plot_stability_chart(undamped_chart, tmp_path / "chart.png")
    (axes,) = drawn["figure"].axes[:1]
    drawn["figure"].canvas.draw()
    legend = axes.get_legend().get_window_extent()
    assert legend.x0 > axes.get_window_extent().x1
