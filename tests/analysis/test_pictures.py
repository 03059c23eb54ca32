"""The pictures' annotations: modes named by what moves in them, labels kept apart."""
from herringbone import load_scene
from herringbone.analysis.campbell import _spread, elastic_frequencies, elastic_modes


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
    places = _spread([100.0, 110.0, 115.0, 900.0, 990.0], gap=50.0, ceiling=1000.0)
    assert all(b - a >= 50.0 - 1e-9 for a, b in zip(places, places[1:]))
    assert places[-1] <= 1000.0 and places[0] == 100.0
    assert _spread([1.0, 5.0], gap=1.0, ceiling=10.0) == [1.0, 5.0]
