"""Speed and parameter sweeps (herringbone.sweep): agreement with single runs, the same table
serial and on Dask, the dynamic factor at a resonance of `herringbone info`, the settle time,
the FMU path, bad arguments; the Campbell crossings; `run --plot` and its progress bar."""
import contextlib
import math
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from helpers import MODELS

import herringbone
from herringbone import cli
from herringbone.analysis.report import resonance_speeds
from herringbone.analysis.stability import largest_multiplier
from herringbone.analysis.sweep import run_sweep, sweep
from herringbone.analysis.sweep_point import Protocol, run_window, timing, window_figures
from herringbone.model.assembly import GearTrainModel, natural_modes

MODELS = MODELS
SHORT = Protocol(settle_time=0.02, window_periods=8, samples_per_period=32)
SPEEDS = [157.08, 400.0, 1000.0]
# the figures without a unit: dynamic factors and shares of the window or of the load
SHARES_AND_FACTORS = ("K_v", "K_v_half", "contact_lost_share", "load_share_left")


def test_sweep_points_agree_with_single_simulate_runs(reference_scene):
    """Each row's figures from herringbone.simulate of the same protocol, sampled as the
    figures are (every figure_interval from t = 0, so its steps stop at other times during the
    settle): equal within the integrator's tolerance, 1e-7 of the static force, but for the
    mesh force's extremes, which the sweep takes from finer samples at each contact switch
    (sweep_point.switch_samples), where the even samples miss up to 2 % of the static force
    (1.5e-2 measured here, F_mesh_min)."""
    table = sweep(reference_scene, speeds=SPEEDS, protocol=SHORT, workers=0, progress=False,
                  method="time")
    assert list(table["w0_pinion"]) == SPEEDS
    for _, row in table.iterrows():
        scene = reference_scene.with_parameters(w0_pinion=row["w0_pinion"])
        when = timing(scene, SHORT)
        assert row["settle_time_s"] == pytest.approx(when.settle, rel=1e-15)
        periods = row["settle_time_s"] * row["mesh_frequency_Hz"]
        assert periods == pytest.approx(round(periods), abs=1e-9) and row["settle_time_s"] >= 0.02
        assert row["window_time_s"] == pytest.approx(8 / row["mesh_frequency_Hz"], rel=1e-12)
        assert row["samples"] == 256 and row["figure_samples"] == 256 * when.refinement > 256
        results = herringbone.simulate(
            scene, stop_time=when.settle + when.window - when.figure_interval,
            output_interval=when.figure_interval, tolerance=SHORT.tolerance)
        first = round(when.settle / when.figure_interval)
        window = {name: values[first:first + when.figure_samples]
                  for name, values in results.items()}
        assert window["time"][0] == pytest.approx(when.settle, abs=1e-12)
        assert len(window["time"]) == when.figure_samples
        force = row["static_mesh_force_N"]
        assert force == pytest.approx(500.0 / GearTrainModel(scene).geometry.radius_pinion)
        single = window_figures(window, force)
        for name, value in single.items():
            scale = 1.0 if name in SHARES_AND_FACTORS else \
                1e6 * force / GearTrainModel(scene).mesh.mean_stiffness() if "dte" in name \
                else force
            if name in ("K_v", "K_v_half") or name.endswith("max_N"):
                assert 0.0 <= row[name] - value <= 2e-2 * scale, name
            elif name == "F_mesh_min_N":
                assert 0.0 <= value - row[name] <= 2e-2 * scale, name
            else:
                assert abs(row[name] - value) <= SHORT.tolerance * scale, name
        assert row["linear_floquet_max"] == pytest.approx(
            float(largest_multiplier(scene, row["w0_pinion"])), rel=1e-12)


# speed (rad/s), settle (s), window (mesh periods), edge ramp (m): a low speed, whose mesh
# period holds some 420 periods of the fastest (13.2 kHz) mode, a normal one, and rounded face
# edges, whose stiffness changes smoothly across the ramp (only where a point enters or leaves
# is sampled finer)
PEAK_POINTS = [(30.0, 0.02, 2, 0.0), (490.0, 0.02, 16, 0.0), (300.0, 0.02, 4, 1e-3)]


@pytest.mark.parametrize("speed, settle, periods, ramp", PEAK_POINTS)
def test_peaks_are_those_of_a_finely_sampled_run(reference_scene, speed, settle, periods, ramp):
    """K_v, F_mesh min and a bearing's peak of a sweep point are those of herringbone.simulate
    over the same window sampled every 0.1 µs (the force falls 0.9 % of the static force a µs
    after a contact switch, its peak: that sampling reads it within 1e-3), within 2e-3 of the
    static force: the fastest mode's ringing resolved (sweep_point.FASTEST_MODE_SAMPLES) and
    each switch sampled finer. 64 samples a mesh period read K_v 1.414 at 30 rad/s where it
    is 1.502, 1.711 at 490 rad/s where it is 1.761. With a 1 mm edge ramp at 300 rad/s the
    sweep reads K_v 1.06191 where the fine run peaks at 1.06197."""
    scene = reference_scene.with_parameters(w0_pinion=speed, edge_ramp=ramp)
    protocol = Protocol(settle_time=settle, window_periods=periods, floquet=False)
    row = sweep(scene, speeds=[speed], protocol=protocol, workers=0, progress=False,
                method="time").iloc[0]
    when = timing(scene, protocol)
    fine = herringbone.simulate(scene, stop_time=when.settle + when.window,
                                output_interval=1e-7, tolerance=protocol.tolerance)
    inside = (fine["time"] >= when.settle - 1e-12) & (fine["time"] <= when.settle + when.window
                                                      - when.interval + 1e-12)
    force = row["static_mesh_force_N"]
    assert row["K_v"] == pytest.approx(fine["F_mesh"][inside].max() / force, abs=2e-3)
    assert row["F_mesh_min_N"] == pytest.approx(fine["F_mesh"][inside].min(), abs=2e-3 * force)
    bearing = np.abs(fine["F_brg_pinion_left"][inside]).max()
    assert row["F_brg_pinion_left_peak_N"] == pytest.approx(bearing, abs=2e-3 * force)


def test_settle_is_the_decay_of_the_least_damped_mode(reference_scene):
    """Default settle: whole mesh periods just past ln(1000)/σ, σ the slowest decay among the
    train's non-rigid eigenvalues (the 113 Hz motor-load torsional mode, σ ≈ 2 1/s)."""
    modes = GearTrainModel(reference_scene).eigenvalues()
    slowest = min([m for m in modes if abs(m) > 1.0 and m.imag >= 0], key=lambda m: -m.real)
    assert abs(slowest.imag) / (2 * math.pi) == pytest.approx(112.9, abs=0.5)
    when = timing(reference_scene, Protocol())
    needed = math.log(1e3) / -slowest.real
    assert needed <= when.settle < needed + when.mesh_period
    assert 3.0 < when.settle < 4.0


@pytest.mark.filterwarnings("error::UserWarning")
def test_a_local_cluster_leaves_port_8787_to_others(reference_scene):
    """A sweep's LocalCluster serves its scheduler's HTTP routes (health, metrics) on a free
    port: with 8787, Dask's default, held by another cluster on the machine, it starts without
    Dask's "Port 8787 is already in use" warning, which a host with warnings as errors turns
    into "Cluster failed to start"."""
    with socket.socket() as holder:
        with contextlib.suppress(OSError):  # (held already: as good)
            holder.bind(("127.0.0.1", 8787))
            holder.listen()
        table = sweep(reference_scene, speeds=[157.08], protocol=SHORT, workers=1,
                      progress=False, method="time")
    assert len(table) == 1


def _started_scheduler(scheduler_file, scheduler, log, deadline_s=60.0):
    """Wait for `dask scheduler` to write its address to `scheduler_file`; fail with the
    scheduler's own last words if it exits first or takes longer than `deadline_s` seconds."""
    deadline = time.monotonic() + deadline_s
    while not scheduler_file.exists():
        if scheduler.poll() is not None or time.monotonic() > deadline:
            pytest.fail(f"dask scheduler did not start (exit code {scheduler.poll()}):\n"
                        f"{log.read_text()[-2000:]}")
        time.sleep(0.1)


@pytest.fixture
def dask_scheduler_and_worker(tmp_path):
    """`dask scheduler` and one `dask worker` (two processes) on 127.0.0.1, shut down after.

    The scheduler binds a port of its own choosing and names it in a scheduler file: a free
    port found here and let go before the scheduler binds it can be taken by another test's
    process in between, and a client then waits on a stranger."""
    scheduler_file = tmp_path / "scheduler.json"
    bin_dir = Path(sys.executable).parent
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    commands = {"scheduler": ["scheduler", "--host", "127.0.0.1", "--port", "0"],
                "worker": ["worker", "--host", "127.0.0.1", "--nworkers", "2", "--nthreads", "1"]}
    processes = []
    try:
        for name, arguments in commands.items():
            with open(tmp_path / f"{name}.log", "w") as log:
                processes.append(subprocess.Popen(
                    [str(bin_dir / "dask"), *arguments, "--scheduler-file", str(scheduler_file),
                     "--no-dashboard"], env=env, cwd=tmp_path, stdout=log,
                    stderr=subprocess.STDOUT))
            if name == "scheduler":
                _started_scheduler(scheduler_file, processes[0], tmp_path / "scheduler.log")
        from dask.distributed import Client
        with Client(scheduler_file=str(scheduler_file), timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)
            address = client.scheduler.address
        yield address
    finally:
        for process in reversed(processes):
            process.terminate()
            process.wait(timeout=30)


def test_serial_local_cluster_and_scheduler_give_identical_tables(reference_scene,
                                                                  dask_scheduler_and_worker):
    """The same four points here, on a LocalCluster of two and on a scheduler with workers
    started by `dask worker`: the same table to the bit; no worker compiled the integrator."""
    from dask.distributed import Client

    from herringbone.integrate.compiled import walk

    speeds = [157.08, 300.0, 650.0, 1200.0]
    serial = sweep(reference_scene, speeds=speeds, protocol=SHORT, workers=0, progress=False,
                   method="time")
    local = sweep(reference_scene, speeds=speeds, protocol=SHORT, workers=2, progress=False,
                  method="time")
    remote = sweep(reference_scene, speeds=speeds, protocol=SHORT,
                   scheduler=dask_scheduler_and_worker, progress=False, method="time")
    pd.testing.assert_frame_equal(serial, local, check_exact=True)
    pd.testing.assert_frame_equal(serial, remote, check_exact=True)
    with Client(dask_scheduler_and_worker) as client:
        compiled = client.run(lambda: any(walk.advance.stats.cache_misses.values()))
    assert len(compiled) == 2 and not any(compiled.values())


def test_dynamic_factor_peaks_at_a_resonance_of_info(reference_scene):
    """Across 350-650 rad/s (30 rad/s apart) K_v peaks within one step of the resonance
    2·f_mesh = 1497 Hz (lateral mode, 470 rad/s) and stands 10 % above the sweep's ends; dte
    peaks within one step of f_mesh = 684 Hz (torsional mesh mode, 430 rad/s)."""
    speeds = np.linspace(350.0, 650.0, 11)
    protocol = Protocol(settle_time=0.2, window_periods=20, floquet=False)
    table = sweep(reference_scene, speeds=speeds, protocol=protocol, workers=0, progress=False,
                  method="time")
    step = speeds[1] - speeds[0]
    frequencies = natural_modes(reference_scene)[0]
    lateral = resonance_speeds(frequencies[3], 10)[2]
    torsional = resonance_speeds(frequencies[2], 10)[1]
    assert frequencies[3] == pytest.approx(1497.3, abs=0.1)
    assert lateral == pytest.approx(470.4, abs=0.1)
    assert frequencies[2] == pytest.approx(683.7, abs=0.1)
    peak = table.loc[table["K_v"].idxmax()]
    assert abs(peak["w0_pinion"] - lateral) <= step
    assert peak["K_v"] > 1.1 * max(table["K_v"].iloc[0], table["K_v"].iloc[-1])
    assert abs(table.loc[table["dte_p2p_um"].idxmax(), "w0_pinion"] - torsional) <= step


def test_contact_loss_share_is_the_time_a_half_is_unloaded():
    """The contact_loss scene (light load, large helix errors) loses its right half part of
    each period; the reference scene never does."""
    scene = herringbone.load_scene(MODELS / "contact_loss.toml")
    table, series = run_sweep(scene, speeds=[157.08], protocol=SHORT, workers=0,
                              progress=False)
    assert 0.2 < table["contact_lost_share"].iloc[0] < 1.0
    assert table["F_mesh_min_N"].iloc[0] >= 0.0
    assert len(series[0]["dte"]) == 256


def test_parameter_grid_of_two(reference_scene):
    """A grid: the last quantity fastest, each row the scene with those values."""
    table = sweep(reference_scene, params={"dbeta_right": [-1e-4, 1e-4], "M_motor": [300, 500]},
                  protocol=SHORT, workers=0, progress=False)
    assert list(zip(table["dbeta_right"], table["M_motor"])) == [
        (-1e-4, 300), (-1e-4, 500), (1e-4, 300), (1e-4, 500)]
    radius = GearTrainModel(reference_scene).geometry.radius_pinion
    assert list(table["static_mesh_force_N"]) == pytest.approx([300 / radius, 500 / radius] * 2)
    assert table["K_v"].iloc[2] != table["K_v"].iloc[0]


@pytest.mark.slow
def test_through_fmu_matches_the_compiled_sweep(reference_scene, scene_fmu):
    """Each point through the FMU with fmpy: the FMU steps the same integrator, stopping at
    every recorded sample from t = 0, so its figures, those of the recorded samples, agree
    with those of the compiled sweep's recorded samples to the bound of the first test (the
    compiled sweep's own figures sample finer: docs/sweeps.md)."""
    table = sweep(reference_scene, speeds=SPEEDS[:2], protocol=SHORT, workers=0, progress=False,
                  method="time")
    through = sweep(reference_scene, speeds=SPEEDS[:2], protocol=SHORT, workers=0,
                    fmu=scene_fmu("reference"), progress=False, method="time")
    assert through.columns.equals(table.columns)
    assert (through["figure_samples"] == through["samples"]).all()
    for row, speed in zip(through.itertuples(), SPEEDS[:2]):
        at = reference_scene.with_parameters(w0_pinion=speed)
        recorded = window_figures(dict(run_window(at, SHORT)), row.static_mesh_force_N)
        assert abs(row.K_v - recorded["K_v"]) <= 1e-9
        assert abs(row.dte_p2p_um - recorded["dte_p2p_um"]) <= 1e-6
    assert (through["K_v"] < table["K_v"]).all()  # the peaks between the recorded samples


def test_shooting_is_the_default_and_agrees_with_settled_time_points(reference_scene):
    """A speed sweep computes the periodic steady state directly by default: a stable row at
    each requested speed, whose K_v and dte peak-to-peak agree with the time protocol settled
    to 1e-6 within 1e-5 relative (at the default residual 1e-3 the time sweep lies 5.8e-6
    (K_v) and 8e-5 (dte peak-to-peak) from the orbits: benchmarks/steady_state.py)."""
    speeds = [300.0, 650.0, 1200.0]
    branch = sweep(reference_scene, speeds=speeds, progress=False)
    assert set(branch["method"]) == {"shooting"} and set(branch["stability"]) == {"stable"}
    assert (branch["floquet_exponent_per_s"] < 0).all() and not branch.attrs["folds"]
    assert np.all(np.diff(branch["w0_pinion"]) > 0)  # no fold: the speed only rises
    table = branch[branch["on_grid"]].reset_index(drop=True)
    assert list(table["w0_pinion"]) == speeds
    settled = Protocol(settle_residual=1e-6, tolerance=1e-10, window_periods=1, floquet=False)
    timed = sweep(reference_scene, speeds=speeds, protocol=settled, workers=0,
                  progress=False, method="time")
    assert set(timed["stability"]) == {"time"}
    for name in ("K_v", "dte_p2p_um"):
        assert np.abs(table[name] / timed[name] - 1.0).max() <= 1e-5, name
    assert np.abs(table["static_mesh_force_N"] - timed["static_mesh_force_N"]).max() == 0.0
    assert np.abs(table["mesh_frequency_Hz"] / timed["mesh_frequency_Hz"] - 1).max() <= 1e-15


def test_a_shooting_sweep_with_rounded_face_edges_agrees_with_settled_time_points(
        reference_scene):
    """With a 1 mm edge ramp the mesh stiffness changes over a quarter of the figures'
    intervals (225 of 896 a period at 300 rad/s), smoothly: the finer switch samples are
    taken where the count of loaded points changes (4 of them), and the orbits' figures stay
    within their period's step budget. K_v and dte peak-to-peak of the branch at 300 and
    800 rad/s agree with the time protocol settled to 1e-6 within 1e-5 relative (measured:
    3e-9); K_v is 1.0593 and 1.1448 there, below the sharp-edged 1.55 and 1.50, the ramp
    smoothing the stiffness jumps that excite the ringing."""
    scene = reference_scene.with_parameters(edge_ramp=1e-3)
    speeds = [300.0, 800.0]
    branch = sweep(scene, speeds=speeds, progress=False)
    table = branch[branch["on_grid"]].reset_index(drop=True)
    assert list(table["w0_pinion"]) == speeds and set(table["stability"]) == {"stable"}
    settled = Protocol(settle_residual=1e-6, tolerance=1e-10, window_periods=1, floquet=False)
    timed = sweep(scene, speeds=speeds, protocol=settled, workers=0, progress=False,
                  method="time")
    for name in ("K_v", "dte_p2p_um"):
        assert np.abs(table[name] / timed[name] - 1.0).max() <= 1e-5, name
    assert list(table["K_v"]) == pytest.approx([1.0593, 1.1448], abs=1e-4)


def test_shooting_where_it_does_not_apply_is_refused_by_name(reference_scene):
    """method="shooting" on a grid of two quantities, a tooth count or unbalanced torques: one
    message naming why and what is allowed; the default then runs the time protocol."""
    with pytest.raises(ValueError, match="two quantities.*method='time'"):
        sweep(reference_scene, params={"zeta_mesh": [0.05], "dbeta_right": [0.0]},
              method="shooting")
    with pytest.raises(ValueError, match="two quantities"):
        sweep(reference_scene, speeds=[300.0, 400.0], params={"zeta_mesh": [0.05]},
              method="shooting")
    with pytest.raises(ValueError, match="z_pinion takes whole numbers"):
        sweep(reference_scene, params={"z_pinion": [10, 11]}, method="shooting")
    unbalanced = reference_scene.with_inputs(M_motor=500.0, M_load=1000.0)
    with pytest.raises(ValueError, match="does not balance"):
        sweep(unbalanced, speeds=[300.0], method="shooting")
    with pytest.raises(ValueError, match="method 'harmonic'; allowed: shooting, time"):
        sweep(reference_scene, speeds=[300.0], method="harmonic")
    table = sweep(reference_scene, params={"zeta_mesh": [0.05], "dbeta_right": [0.0]},
                  protocol=SHORT, workers=0, progress=False)
    assert list(table["method"]) == ["time"]


@pytest.fixture
def no_sweep_work(monkeypatch):
    """A point run or a branch followed fails the test: every check must come first."""
    import herringbone.analysis.sweep as module

    def refuse(*args, **kwargs):
        raise AssertionError("the sweep began before its arguments were checked")

    monkeypatch.setattr(module, "run_point", refuse)
    monkeypatch.setattr(module, "shooting_sweep", refuse)


@pytest.mark.parametrize("arguments, culprit", [
    ({"speeds": [300, 300]}, "speeds holds 300 more than once; allowed: distinct values"),
    ({"params": {"zeta_mesh": [0.02, 0.05, 0.02]}}, "zeta_mesh holds 0.02 more than once"),
    ({"params": ["zeta_mesh"]}, "params is a list (['zeta_mesh']); allowed: a dict"),
    ({"speeds": [300.0], "protocol": {"settle_time": 0.01}}, "protocol is a dict"),
    ({"speeds": [300.0], "foo": 1}, "unknown option foo; allowed: workers, scheduler"),
    ({"speeds": [300.0], "method": "time", "foo": 1}, "unknown option foo; allowed:"),
    ({"speeds": [300.0], "workers": -1}, "workers is -1; allowed: a whole number >= 0"),
    ({"speeds": [300.0], "workers": 2}, "workers=2: a sweep by shooting follows its branch"),
    ({"speeds": [300.0], "scheduler": "tcp://127.0.0.1:1"}, "scheduler='tcp://127.0.0.1:1'"),
    ({"speeds": [300.0], "method": "time", "doubling": False}, "doubling=False: allowed:"),
])
def test_a_bad_sweep_argument_is_one_value_error_before_any_work(arguments, culprit,
                                                                  reference_scene,
                                                                  no_sweep_work):
    """The same refusal whichever method would run: the shooting path took unknown options
    and workers it cannot use in silence, a list or dict in the wrong place ended in an
    AttributeError, a repeated speed in "cannot convert float NaN to integer"."""
    with pytest.raises(ValueError) as error:
        sweep(reference_scene, progress=False, **arguments)
    message = str(error.value)
    assert culprit in message and "allowed" in message and "\n" not in message


def test_a_sweep_of_no_scene_is_a_scene_error(no_sweep_work):
    with pytest.raises(herringbone.SceneError, match="scene must be a herringbone.Scene, got "
                                                     "str 'reference'; load one"):
        sweep("reference", speeds=[300.0, 400.0])


def test_a_tooth_count_sweep_keeps_the_motor_torque_and_the_load_follows_the_ratio(
        reference_scene):
    """z_pinion changes u = z_wheel/z_pinion at every point, so no one M_load balances them
    all: on a balanced scene the load torque follows, M_load = u·M_motor, and each point runs
    steadily with the motor's 500 N·m on the pinion's pitch radius."""
    from herringbone.analysis.sweep import Point, scene_at

    at = scene_at(reference_scene, Point(0, (("z_pinion", 11),)))
    assert at.inputs.at(0.0) == pytest.approx((500.0, 500.0 * 36 / 11), rel=1e-15)
    table = sweep(reference_scene, params={"z_pinion": [10, 11, 12]}, method="time",
                  workers=0, progress=False)
    radii = [GearTrainModel(reference_scene.with_parameters(z_pinion=z)).geometry.radius_pinion
             for z in (10, 11, 12)]
    assert table.static_mesh_force_N.tolist() == pytest.approx([500.0 / r for r in radii],
                                                               rel=1e-12)
    assert table.window_drift.max() < 1e-4  # settled: the train neither speeds up nor slows


def test_a_sweep_whose_points_have_no_steady_running_is_refused_before_any_work(
        reference_scene, no_sweep_work):
    """Torques that do not balance (the train runs away from the speed its row names),
    M_motor <= 0 (the back flanks, on which the model has no contact), a standing pinion or
    an input table: one message before any point runs, by either method; one torque swept
    on a balanced scene still moves the other with it."""
    from herringbone.analysis.sweep import check_sweep

    unbalanced = reference_scene.with_inputs(M_motor=500.0, M_load=100.0)
    for method in (None, "time"):
        with pytest.raises(ValueError, match=r"M_load = 100 N·m does not balance M_motor = "
                                             r"500 N·m .*allowed: M_load = u·M_motor = 1800 N·m$"):
            sweep(unbalanced, speeds=[300.0, 400.0], method=method, workers=0)
    with pytest.raises(ValueError, match=r"at M_motor = 250, M_load = 1800: M_load = 1800 "
                                         r"N·m does not balance M_motor = 250 N·m"):
        sweep(reference_scene, params={"M_motor": [250.0, 500.0], "M_load": [900.0, 1800.0]},
              workers=0)
    negative = reference_scene.with_inputs(M_motor=-500.0, M_load=-1800.0)
    for scene, params in ((negative, None), (reference_scene, {"M_motor": [-100.0, 100.0]})):
        with pytest.raises(ValueError, match="M_motor = -\\d+ N·m: .*negative .*back flanks"):
            sweep(scene, speeds=[300.0, 600.0] if params is None else None, params=params)
    standing = reference_scene.with_parameters(w0_pinion=0.0)
    with pytest.raises(ValueError, match="w0_pinion is 0: a sweep point needs a turning"):
        sweep(standing, params={"zeta_mesh": [0.02, 0.05]}, method="time", workers=0)
    stepped = reference_scene.with_inputs(table=[[0.0, 500.0, 1800.0], [0.01, 600.0, 2160.0]])
    with pytest.raises(ValueError, match="needs constant input torques"):
        sweep(stepped, speeds=[300.0, 400.0], method="time", workers=0)
    assert check_sweep(standing, speeds=[300.0]) == "shooting"  # the speeds set w0_pinion
    assert check_sweep(reference_scene, params={"M_load": [900.0, 3600.0]}) == "shooting"
    assert check_sweep(reference_scene, speeds=[300.0, 400.0],
                       params={"M_motor": [250.0, 500.0]}) == "time"


@pytest.mark.parametrize("arguments, culprit", [
    (["--speeds", "100", "50", "3"], "--speeds"),
    (["--speeds", "0", "50", "3"], "--speeds"),
    (["--speeds", "10", "50", "2.5"], "COUNT 2.5"),
    (["--speeds", "10", "nan", "3"], "--speeds"),
    (["--rpm"], "--rpm"),
    ([], "nothing to sweep"),
    (["--param", "no_such", "1", "2", "3"], "no_such: unknown parameter"),
    (["--param", "zeta_mesh", "-1", "0.1", "3"], "zeta_mesh"),
    (["--param", "z_pinion", "0", "2", "3"], "z_pinion"),
    (["--speeds", "10", "50", "3", "--param", "w0_pinion", "1", "2", "2"], "w0_pinion"),
    (["--speeds", "10", "50", "3", "--param", "beta", "0.3", "0.4", "2", "--param",
      "eps_q", "0.5", "0.6", "2"], "at most 2"),
    (["--speeds", "10", "50", "3", "--workers", "-1"], "workers"),
    (["--speeds", "10", "50", "3", "--scheduler", "localhost"], "scheduler"),
    (["--speeds", "10", "50", "3", "--window-periods", "0"], "--window-periods"),
    (["--speeds", "10", "50", "3", "--settle-residual", "2"], "--settle-residual"),
    (["--speeds", "10", "50", "3", "--through-fmu", "missing.fmu"], "--through-fmu"),
])
def test_bad_sweep_arguments_get_one_line_and_exit_code_2(arguments, culprit, capsys):
    code = cli.main(["sweep", str(MODELS / "reference.toml"), "--no-progress", *arguments])
    error = capsys.readouterr().err
    assert code == 2
    assert error.startswith("herringbone sweep: ") and error.count("\n") == 1
    assert culprit in error and "allowed" in error


def test_sweep_command_writes_table_and_pictures(tmp_path, capsys):
    code = cli.main(["sweep", str(MODELS / "torsional.toml"), "--speeds", "2000", "6000", "3",
                     "--rpm", "--settle-time", "0.01", "--window-periods", "5", "--method",
                     "time", "--workers", "0", "--no-progress", "-o", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0 and "settle" in out
    table = pd.read_csv(tmp_path / "torsional_sweep_w0_pinion.csv")
    assert table["speed_rpm"].to_numpy() == pytest.approx([2000, 4000, 6000])
    assert "F_brg_pinion_left_peak_N" not in table  # rigid bearings: no bearing outputs
    for name in ("resonance", "waterfall"):
        assert (tmp_path / f"torsional_sweep_w0_pinion_{name}.png").stat().st_size > 10_000


def test_campbell_crossings_are_the_resonance_speeds_of_info(tmp_path, capsys):
    output = tmp_path / "campbell.png"
    assert cli.main(["campbell", str(MODELS / "reference.toml"), "--speeds", "400", "500",
                     "2", "-o", str(output)]) == 0
    crossings, ringing = capsys.readouterr().out.split("those that ring")
    lines = [line for line in crossings.splitlines() if "k = " in line]
    # info: 683.71 Hz at k = 1 429.6 rad/s, 2059.40 Hz k = 3 431.3, 1497.33 Hz k = 2 470.4
    assert [line.split("(")[1].split("rad/s")[0].strip() for line in lines] == ["429.6", "431.3",
                                                                          "470.4"]
    # of which the first rings (10 % of the static force), and the 6th harmonic on 4397 Hz
    # and the 14th to 16th on the 10419 Hz mesh mode (rough)
    assert [line.split("(")[1].split("rad/s")[0].strip() for line in ringing.splitlines()
            if "k = " in line] == ["409.1", "429.6", "436.4", "460.5", "467.6"]
    assert output.stat().st_size > 10_000
    assert cli.main(["campbell", str(MODELS / "reference.toml"), "--speeds", "500", "400",
                     "2"]) == 2
    assert capsys.readouterr().err.startswith("herringbone campbell: --speeds")


def assert_the_bar_leaves_the_reference_unchanged(scene, stop_time, output_interval):
    """The reference's run with the progress bar gives its numbers to the bit."""
    from herringbone.analysis.run_progress import reference_simulate_with_progress

    plain = herringbone.reference_simulate(scene, stop_time=stop_time,
                                           output_interval=output_interval)
    watched = reference_simulate_with_progress(scene, stop_time=stop_time,
                                               output_interval=output_interval)
    for name in plain:
        assert np.array_equal(plain[name], watched[name]), name


def test_run_plot_and_progress_leave_the_numbers_unchanged(tmp_path, capsys):
    scene = herringbone.load_scene(MODELS / "contact_loss.toml")
    assert_the_bar_leaves_the_reference_unchanged(scene, 0.004, 2e-5)
    assert "s simulated" in capsys.readouterr().err
    csv = tmp_path / "run.csv"
    assert cli.main(["run", str(MODELS / "contact_loss.toml"), "--stop-time", "0.004",
                     "--output-interval", "2e-5", "--plot", "-o", str(csv)]) == 0
    for name in ("run_time.png", "run_spectrum.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_the_progress_bar_follows_the_references_check_with_the_same_numbers(capsys):
    """2 ms of the jump scene lift the mesh off and land it twice: reference_simulate runs it
    again ten times tighter (integrate/global_error.py), and so does the run with the bar,
    which starts again named as the check."""
    scene = herringbone.load_scene(MODELS / "jump_resonance.toml")
    assert_the_bar_leaves_the_reference_unchanged(scene, 0.002, 1e-4)
    assert "check jump_resonance (steps to 5e-12)" in capsys.readouterr().err


def test_resonance_curve_draws_a_branch_by_stability(tmp_path):
    """A branch table: stable stretches solid, unstable dashed (each stretch joined to the next
    point), folds crossed, time sweeps as triangles; the picture is written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from herringbone.analysis.sweep_plots import draw_branch, plot_resonance_curve

    table = pd.DataFrame({"w0_pinion": [1.0, 2.0, 3.0, 2.5, 2.0, 3.0],
                          "K_v": [1.0, 1.2, 1.5, 1.8, 2.0, 1.9],
                          "dte_p2p_um": [1.0, 2.0, 3.0, 4.0, 5.0, 4.5],
                          "stability": ["stable", "stable", "unstable", "unstable", "stable",
                                        "stable"],
                          "event": ["", "", "fold", "", "fold", ""]})
    table["speed_rpm"] = table["w0_pinion"] * 30 / math.pi
    figure, axes = plt.subplots(2, 1)
    draw_branch(axes, table, [("K_v", "k"), ("dte_p2p_um", "C2")])
    lines = {line.get_label(): line for line in axes[0].get_lines()}
    stable, unstable = lines["K_v, stable orbits"], lines["K_v, unstable orbits"]
    assert stable.get_linestyle() == "-" and unstable.get_linestyle() == "--"
    assert list(np.isnan(stable.get_ydata())) == [False, False, False, True, False, False]
    assert list(np.isnan(unstable.get_ydata())) == [True, True, False, False, False, True]
    assert list(lines["fold (jump)"].get_ydata()) == [1.5, 2.0]
    # the lower panel's legend says what it draws, not the table's column name
    assert {line.get_label() for line in axes[1].get_lines()} >= {
        "dte peak-to-peak, stable orbits", "dte peak-to-peak, unstable orbits"}
    plt.close(figure)
    up = table.iloc[:3].assign(stability="time")
    path = tmp_path / "curve.png"
    plot_resonance_curve(table, path, [], "branch", sweeps={"up": up})
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_parameter_branch_picture_names_its_unit_and_only_the_lines_it_has(tmp_path,
                                                                             monkeypatch):
    """A branch over a torque with stable orbits only: the abscissa reads the torque's unit,
    and the legend has no entry for unstable orbits the picture does not draw."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from herringbone.analysis import sweep_plots

    table = pd.DataFrame({"M_motor": [200.0, 500.0, 800.0], "K_v": [1.69, 1.685, 1.682],
                          "stability": ["stable"] * 3, "event": [""] * 3})
    drawn = {}
    monkeypatch.setattr(sweep_plots, "_save", lambda figure, path: drawn.update(
        figure=figure))
    sweep_plots.plot_parameter_sweep(table, ["M_motor"], tmp_path / "branch.png", "torque")
    axes = drawn["figure"].axes[0]
    assert axes.get_xlabel() == "M_motor, N.m"
    assert [text.get_text() for text in axes.get_legend().get_texts()] == [
        "K_v, stable orbits"]
    plt.close(drawn["figure"])


def test_the_summary_counts_the_points_no_orbit_converged_on(reference_scene):
    """Points where shooting found no orbit (run by time integration instead) are counted
    apart from the orbits, and only where there are any."""
    from herringbone.analysis.sweep_report import describe

    table = pd.DataFrame({"w0_pinion": [500.0, 550.0, 600.0], "speed_rpm": [4775.0] * 3,
                          "K_v": [1.4, 1.5, 1.6], "stability": ["stable", "time", "time"],
                          "mesh_periods": [1, 1, 1], "event": [""] * 3,
                          "contact_lost_share": [0.0] * 3})
    table.attrs.update(continued="w0_pinion", folds=[])
    line = describe(reference_scene, table, 1.0).splitlines()[1]
    assert line.endswith("1 stable, 0 unstable orbits; 2 points where no orbit converged, run "
                         "by time integration"), line


def test_the_summary_of_a_branch_reads_k_v_on_what_a_run_settles_on(reference_scene):
    """A branch whose largest K_v is on an unstable orbit: the summary's K_v range and peak are
    those of the stable orbits, and the period doublings and their 2T branches are named."""
    from herringbone.analysis.sweep_report import describe

    table = pd.DataFrame({"zeta_mesh": [0.02, 0.03, 0.04, 0.03, 0.02],
                          "speed_rpm": [4775.0] * 5, "K_v": [1.4, 1.5, 1.6, 9.0, 2.5],
                          "stability": ["stable", "stable", "stable", "unstable", "stable"],
                          "mesh_periods": [1, 1, 1, 2, 2], "event": [""] * 5,
                          "contact_lost_share": [0.0] * 5})
    table.attrs.update(continued="zeta_mesh", folds=[], period_doublings=[0.0305],
                       folds_2T=[0.031])
    lines = describe(reference_scene, table, 1.0).splitlines()
    assert lines[1].endswith("3 stable, 0 unstable orbits")  # no time integration to report
    assert lines[2] == "period doublings in zeta_mesh at 0.0305"
    assert lines[3] == "their 2T branches: 1 stable, 1 unstable orbits"
    assert lines[4] == "folds of the 2T branches at 0.031"
    assert lines[5] == ("K_v from 1.4000 to 2.5000 (stable orbits); largest at zeta_mesh = "
                        "0.02")


def test_the_summary_of_a_branch_on_which_no_orbit_converged_names_them(reference_scene,
                                                                        tmp_path):
    """A shooting table whose every point fell back to time integration has no stable or
    unstable row and none of the time table's settle columns: its summary counts them as
    such (it raised KeyError 'settle_time_s'), and its table and picture are written."""
    from herringbone.analysis.sweep_report import describe, write_outputs

    table = pd.DataFrame({"w0_pinion": [300.0, 450.0, 600.0], "speed_rpm": [2865.0, 4297.0,
                                                                            5730.0],
                          "K_v": [1.4, 1.5, 1.6], "dte_p2p_um": [5.0, 6.0, 7.0],
                          "dte_rms_um": [1.0, 1.2, 1.4], "contact_lost_share": [0.0] * 3,
                          "stability": ["time"] * 3, "method": ["time"] * 3,
                          "on_grid": [True] * 3, "event": [""] * 3, "mesh_periods": [1] * 3})
    table.attrs.update(continued="w0_pinion", folds=[])
    lines = describe(reference_scene, table, 1.0).splitlines()
    assert lines[1].endswith("0 stable, 0 unstable orbits; 3 points where no orbit converged, "
                             "run by time integration"), lines
    assert lines[2].startswith("K_v from 1.4000 to 1.6000; largest at w0_pinion = 600")
    written = write_outputs(reference_scene, table, None, tmp_path)
    assert [path.name for path in written] == ["reference_sweep_w0_pinion.csv",
                                               "reference_sweep_w0_pinion_resonance.png"]
    # the chained time sweeps were only drawn: their figures are kept beside the table
    up, down = table.assign(K_v=[1.3, 1.5, 1.7]), table.iloc[::-1]
    written = write_outputs(reference_scene, table, None, tmp_path, {"up": up, "down": down})
    assert [path.name for path in written[:3]] == ["reference_sweep_w0_pinion.csv",
                                                   "reference_sweep_w0_pinion_time_up.csv",
                                                   "reference_sweep_w0_pinion_time_down.csv"]
    kept = pd.read_csv(written[1])
    assert kept["w0_pinion [rad/s]"].tolist() == [300.0, 450.0, 600.0]
    assert kept["K_v"].tolist() == [1.3, 1.5, 1.7]


def test_a_branch_lost_and_begun_again_is_said_so_and_drawn_with_no_line_across(
        reference_scene):
    """Where the continuation could not go on (an undamped train's resonance, say) and
    shooting began again further on, the first orbit there is flagged "restart": the summary
    names where the branch was lost, its K_v line says that a peak in that gap is not in its
    figures, and the curve draws no line across what nobody computed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from herringbone.analysis.sweep_plots import draw_branch
    from herringbone.analysis.sweep_report import describe

    table = pd.DataFrame({"w0_pinion": [300.0, 303.0, 306.1, 450.0, 600.0],
                          "speed_rpm": [2865.0, 2893.0, 2923.0, 4297.0, 5730.0],
                          "K_v": [1.2, 1.6, 2.0, 1.4, 15.0],
                          "stability": ["stable", "stable", "stable", "time", "stable"],
                          "mesh_periods": [1] * 5, "event": ["", "", "", "", "restart"],
                          "contact_lost_share": [0.0] * 5})
    table.attrs.update(continued="w0_pinion", folds=[])
    lines = describe(reference_scene, table, 1.0).splitlines()
    assert ("the branch was lost past 306.1 rad/s: no orbit followed on to 600 rad/s, where "
            "shooting began again (nothing computed between them)") in lines
    (k_v,) = [line for line in lines if line.startswith("K_v from")]
    assert k_v.endswith("; nothing computed from 306.1 rad/s to 600 rad/s, where the branch was "
                        "lost: a peak there is not in these figures")
    figure, axes = plt.subplots(1, 1)
    draw_branch([axes], table, [("K_v", "k")])
    (stable,) = [line for line in axes.get_lines() if line.get_label() == "K_v, stable orbits"]
    x, y = stable.get_xdata(), stable.get_ydata()
    # the segments drawn, between neighbours that are both numbers: along the orbits up to
    # 2923 rpm, none into the time point (4297 rpm) nor across to the restart (5730 rpm)
    drawn = [(float(x[k]), float(x[k + 1])) for k in range(len(x) - 1)
             if np.isfinite(y[k]) and np.isfinite(y[k + 1])]
    assert drawn == [(2865.0, 2893.0), (2893.0, 2923.0)], drawn
    axes.clear()
    draw_branch([axes], table.drop(index=3), [("K_v", "k")])  # the restart right after
    (stable,) = [line for line in axes.get_lines() if line.get_label() == "K_v, stable orbits"]
    x, y = stable.get_xdata(), stable.get_ydata()
    assert [(float(x[k]), float(x[k + 1])) for k in range(len(x) - 1)
            if np.isfinite(y[k]) and np.isfinite(y[k + 1])] == [(2865.0, 2893.0),
                                                                 (2893.0, 2923.0)]
    plt.close(figure)


def test_a_resonance_the_sweep_steps_over_is_said_so(reference_scene):
    """The reference scene's 113 Hz mode (ζ 0.3 %) rings at 23.6 rad/s with k = 3: a sweep
    from 20 to 100 rad/s in 20 speeds computes 20 and 24.2 rad/s beside it, 18 % apart, and its
    line says the peak may lie between them and how to look there (a drive-train engineer
    read such a table as no resonance at 23.6 rad/s, whose peak is K_v 1.64); the primary
    resonance at 70.9 rad/s, about which the continuation computed points 0.1 rad/s apart,
    says nothing of the kind."""
    from herringbone.analysis.sweep_report import describe

    speeds = np.sort(np.concatenate([np.linspace(20.0, 100.0, 20), [70.85, 70.95, 71.05]]))
    table = pd.DataFrame({"w0_pinion": speeds, "speed_rpm": speeds * 30 / math.pi,
                          "K_v": 1.5, "stability": "stable", "mesh_periods": 1, "event": "",
                          "contact_lost_share": 0.0})
    table.attrs.update(continued="w0_pinion", folds=[])
    lines = describe(reference_scene, table, 1.0).splitlines()
    (third,) = [line for line in lines if line.startswith("resonance k·f_mesh = f_n at 226 rpm")]
    assert third.endswith("; the nearest points computed, 20 and 24.21 rad/s, lie further apart "
                          "than its width (±0.29 %): its peak may lie between them (`herringbone "
                          "sweep reference --speeds 22.46 24.82 20` looks there)")
    (primary,) = [line for line in lines if line.startswith("resonance k·f_mesh = f_n at 677 rpm")]
    assert primary.endswith("of the static force")


def test_a_speed_sweep_names_its_peaks_largest_first(reference_scene):
    """Beside the largest K_v, a speed sweep's summary names every row whose K_v exceeds both
    neighbours', largest first, along the branch's stable orbits (an unstable orbit between
    them is not a neighbour): the engineer's session had to find them in the CSV."""
    from herringbone.analysis.sweep_report import describe

    speeds = np.array([100.0, 110.0, 120.0, 125.0, 130.0, 140.0, 150.0])
    table = pd.DataFrame({"w0_pinion": speeds, "speed_rpm": speeds * 30 / math.pi,
                          "K_v": [1.5, 1.8, 1.6, 2.5, 1.7, 2.0, 1.9],
                          "stability": ["stable", "stable", "stable", "unstable", "stable",
                                        "stable", "stable"],
                          "mesh_periods": 1, "event": "", "contact_lost_share": 0.0})
    table.attrs.update(continued="w0_pinion", folds=[])
    lines = describe(reference_scene, table, 1.0).splitlines()
    assert ("peaks of K_v (largest first; a peak between the points computed is not among "
            "them): 2.0000 at 140 rad/s, 1.8000 at 110 rad/s") in lines


def test_the_resonance_curves_legends_stand_beside_the_data(tmp_path, monkeypatch):
    """Inside its panel, a legend of a dozen orders k hid the curve's low speeds (the reference
    scene's peak of K_v 2.0 at 677 rpm, swept from 20 to 1500 rad/s): each panel's legend
    stands to the right of the panel, and the orders are listed once, on the top one."""
    import matplotlib

    matplotlib.use("Agg")
    from herringbone.analysis import sweep_plots
    from herringbone.analysis.excitation import Resonance

    drawn = []
    monkeypatch.setattr(sweep_plots, "_save", lambda figure, path: drawn.append(figure))
    speeds = np.linspace(20.0, 1500.0, 20)
    table = pd.DataFrame({"w0_pinion": speeds, "speed_rpm": speeds * 30 / math.pi,
                          "K_v": 1.5 + 0.1 * np.sin(speeds), "dte_p2p_um": 15.0 + speeds / 100,
                          "dte_rms_um": 5.0 + speeds / 300, "contact_lost_share": 0.0})
    found = [Resonance(2 * math.pi * f / (k * 10), k, f, 0.1, 0.05, 0.0)
             for f in (112.9, 683.7) for k in range(1, 13)]
    sweep_plots.plot_resonance_curve(table, tmp_path / "curve.png",
                                     sorted(found, key=lambda r: r.speed), "curve")
    (figure,) = drawn
    figure.canvas.draw()
    for panel in figure.axes[:2]:
        legend = panel.get_legend().get_window_extent()
        assert legend.x0 >= panel.get_window_extent().x1
    entries = [[text.get_text() for text in panel.get_legend().get_texts()]
               for panel in figure.axes[:2]]
    assert [e for e in entries[0] if e.startswith("k·f_mesh")] == [
        f"k·f_mesh = f_n, k = {k}" for k in range(1, 13)]
    assert not [e for e in entries[1] if e.startswith("k·f_mesh")]


def test_resonance_marks_list_their_orders_in_order_and_keep_their_labels_apart():
    """The legend gives the orders k = 1, 2, 3 in that order (it listed them as the speeds
    met them: 3, 2, 1), and two resonances 17 rpm apart (4102 and 4119 rpm on the reference
    scene) get labels a label's height apart instead of one over the other."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from herringbone.analysis.excitation import Resonance
    from herringbone.analysis.sweep_plots import LABEL_GAP, mark_resonances

    figure, axes = plt.subplots(2, 1)
    found = [Resonance(2 * math.pi * f / (k * 10), k, f, 0.1, 0.05, 0.0)
             for f in (683.7, 1497.3, 2059.4, 4397.2) for k in (1, 2, 3)]
    mark_resonances(axes, sorted(found, key=lambda r: r.speed), 100.0, 1000.0)
    labels = [line.get_label() for line in axes[0].get_lines()
              if not line.get_label().startswith("_")]
    assert labels == [f"k·f_mesh = f_n, k = {k}" for k in (1, 2, 3)]
    places = [text.xyann[0] for text in axes[0].texts]
    gap = LABEL_GAP * 900.0 * 30.0 / math.pi
    assert all(b - a >= gap * (1 - 1e-9) for a, b in zip(places, places[1:])), places
    assert [text.get_text() for text in axes[0].texts][3:5] == [" 684 Hz", " 2059 Hz"]
    plt.close(figure)


def test_the_largest_k_v_of_a_grid_gives_the_speed_in_rpm_beside_the_speed():
    """A grid of speed and torque: "w0_pinion = 450 rad/s (4297 rpm), M_motor = 500 N.m",
    the rpm beside the speed it converts, not after the torque."""
    from herringbone.analysis.sweep import resonation_summary

    table = pd.DataFrame({"w0_pinion": [300.0, 450.0], "M_motor": [500.0, 500.0],
                          "speed_rpm": [2865.0, 4297.0], "K_v": [1.2, 1.5]})
    assert resonation_summary(table) == ("w0_pinion = 450 rad/s (4297 rpm), "
                                         "M_motor = 500 N.m")


def test_a_summary_through_the_fmu_says_its_figures_are_of_the_recorded_samples(
        reference_scene):
    """Through the FMU a point's figures are those of its recorded samples (fmpy reads the
    FMU's outputs there), which read the ringing's peaks low: the summary says so there, and
    only there."""
    from herringbone.analysis.sweep_report import describe

    table = sweep(reference_scene, speeds=SPEEDS[:1], protocol=SHORT, workers=0,
                  progress=False, method="time")
    said = "through the FMU: the figures are those of the FMU's outputs at the recorded samples"
    assert said in describe(reference_scene, table, 1.0, through_fmu=True)
    assert said not in describe(reference_scene, table, 1.0)


def test_the_tables_swept_columns_carry_their_units(reference_scene):
    """The CSV's header gives a swept column's unit ("w0_pinion [rad/s]"); the API's table
    gives it in attrs["units"], by either method, as the other columns name theirs."""
    by_shooting = sweep(reference_scene, speeds=[200.0, 400.0], progress=False)
    assert by_shooting.attrs["units"] == {"w0_pinion": "rad/s"}
    grid = sweep(reference_scene, speeds=SPEEDS[:1], params={"M_motor": [300.0, 500.0]},
                 protocol=SHORT, workers=0, progress=False)
    assert grid.attrs["units"] == {"M_motor": "N.m"}


def test_evenly_loaded_halves_have_the_mesh_s_dynamic_factor(reference_scene):
    """On the symmetric reference scene (no lead error, no stagger) the halves carry the same
    force at every instant: each half's peak is half the mesh force's, K_v_half is K_v and
    load_share_left is 0.5, to rounding (1e-9; measured 2e-14), by either method; the summary
    then says nothing of the halves."""
    from herringbone.analysis.sweep_report import describe

    branch = sweep(reference_scene, speeds=[300.0], progress=False)
    timed = sweep(reference_scene, speeds=[300.0], protocol=SHORT, workers=0, progress=False,
                  method="time")
    for table in (branch, timed):
        row = table.iloc[0]
        assert row["K_v_half"] == pytest.approx(row["K_v"], rel=1e-9)
        assert row["F_mesh_left_max_N"] == pytest.approx(0.5 * row["F_mesh_max_N"], rel=1e-9)
        assert row["F_mesh_right_max_N"] == pytest.approx(0.5 * row["F_mesh_max_N"], rel=1e-9)
        assert row["load_share_left"] == pytest.approx(0.5, abs=1e-9)
    assert "K_v_half" not in describe(reference_scene, branch, 1.0)


def test_a_lead_error_loads_one_half_beyond_what_k_v_says(reference_scene):
    """A lead error of 1e-3 rad on the left half at 300 rad/s: the left half carries 67 % of
    the load and peaks at 1.737 times its static share (half the static force), while K_v, of
    the two halves' sum, falls to 1.408 (1.551 without the error). A time point's K_v_half
    and load_share_left are those of herringbone.simulate over the same window sampled every
    0.1 µs, within 2e-3 of the static force (4e-3 of K_v_half; measured 1e-5) and 2e-4
    (measured 4e-5: the window's means from its evenly spaced samples). The orbit's agree
    with the time protocol settled to 1e-6 (1e-6; measured 8e-9), and the summary names the
    half's factor and the share."""
    from herringbone.analysis.sweep_report import describe

    scene = reference_scene.with_parameters(dbeta_left=1e-3, w0_pinion=300.0)
    protocol = Protocol(settle_time=0.02, window_periods=4, floquet=False)
    row = sweep(scene, speeds=[300.0], protocol=protocol, workers=0, progress=False,
                method="time").iloc[0]
    when = timing(scene, protocol)
    fine = herringbone.simulate(scene, stop_time=when.settle + when.window,
                                output_interval=1e-7, tolerance=protocol.tolerance)
    inside = (fine["time"] >= when.settle - 1e-12) & (fine["time"] < when.settle + when.window
                                                      - 1e-12)
    left, right, total = (np.asarray(fine[name])[inside]
                          for name in ("F_mesh_left", "F_mesh_right", "F_mesh"))
    half_static = 0.5 * row["static_mesh_force_N"]
    assert row["K_v_half"] == pytest.approx(max(left.max(), right.max()) / half_static,
                                            abs=4e-3)
    assert row["load_share_left"] == pytest.approx(left.mean() / total.mean(), abs=2e-4)
    branch = sweep(scene, speeds=[300.0], progress=False)
    orbit = branch[branch["on_grid"]].iloc[0]
    settled = Protocol(settle_residual=1e-6, tolerance=1e-10, window_periods=1, floquet=False)
    timed = sweep(scene, speeds=[300.0], protocol=settled, workers=0, progress=False,
                  method="time").iloc[0]
    for name in ("K_v", "K_v_half", "load_share_left"):
        assert orbit[name] == pytest.approx(timed[name], abs=1e-6), name
    assert orbit["load_share_left"] == pytest.approx(0.673, abs=1e-3)
    assert orbit["K_v_half"] == pytest.approx(1.737, abs=1e-3)
    assert orbit["K_v"] == pytest.approx(1.408, abs=1e-3)
    assert ("K_v_half from 1.7372 to 1.7372 (stable orbits), largest at w0_pinion = 300 rad/s "
            "(2865 rpm): the more loaded helix half, its peak over half the static force (what "
            "a tooth bears, where K_v, of the two halves' sum, may fall); the left half carries "
            "67.3 % of the load (load_share_left)") in describe(scene, branch, 1.0).splitlines()


def test_a_train_too_lightly_damped_for_the_derived_settle_is_refused_before_any_work():
    """undamped's least-damped mode decays at a rate that is rounding (8e-13 1/s on one
    machine, 6e-13 on another): the derived settle would be some 1e13 s and the sweep by time
    never ended; it is refused before any work, naming what to give, and runs with the
    settle given."""
    scene = herringbone.load_scene(MODELS / "undamped.toml")
    with pytest.raises(ValueError, match=r"undamped at w0_pinion = 300: its least-damped mode "
                                         r"decays at \d\.?\d*e-1[2-4] 1/s, so the settle to "
                                         r"0.001 of the start's transient would be "
                                         r"\d\.?\d*e\+1[1-5] s .*give the settle "
                                         r"\(--settle-time"):
        sweep(scene, speeds=[300.0, 500.0], method="time", workers=0, progress=False)
    given = Protocol(settle_time=0.002, window_periods=4, floquet=False)
    table = sweep(scene, speeds=[300.0], method="time", protocol=given, workers=0,
                  progress=False)
    assert table["settle_time_s"].iloc[0] == pytest.approx(0.002, rel=0.1)
