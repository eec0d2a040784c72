"""Closed forms of the stage model (docs/world.md): switch states and edges, profiles."""
import pytest

from opentmcl.motion.stage import FAR, Profile, Stage, home_switch, left_switch, right_switch


def test_switch_intervals():
    """docs/scenarios.md: left active left of its position, right to the right, home centred."""
    assert left_switch(-100).active(-100) and not left_switch(-100).active(-99)
    assert left_switch(-100, 50).active(-150) and not left_switch(-100, 50).active(-151)
    assert right_switch(100).active(FAR - 1) and not right_switch(100).active(99)
    h = home_switch(0, 10)
    assert (h.lo, h.hi, h.centre) == (-5, 5, 0)


def test_edges_depend_on_the_state_and_hysteresis():
    """A released switch changes at lo / hi, an actuated one at lo - h - 1 / hi + h + 1."""
    h = home_switch(0, 10, hysteresis=3)
    assert h.edges(False) == (-5, 5)
    assert h.edges(True) == (-9, 9)
    assert h.active(-8, was=True) and not h.active(-8, was=False)
    assert left_switch(0).edges(False) == (0,)        # the far end is beyond any position


def test_circular_stage_repeats_every_turn():
    """A circular axis (scenarios.md `steps_per_turn`): the home switch repeats each turn; the edge
    candidates are the repetitions in this turn and the turns on either side."""
    st = Stage(home=home_switch(0, 100), steps_per_turn=1000)
    assert st.active(st.home, 1020, False) and st.active(st.home, -980, False)
    assert not st.active(st.home, 1500, False)
    assert sorted(st.edge_candidates(1500, st.home, False)) == [50, 950, 1050, 1950, 2050, 2950]


def test_profiles():
    """Signals: steps hold from their x on, ramps interpolate; the next change of the rounded
    value is found in closed form (input-change events)."""
    steps = Profile([(1.0, 5), (2.0, 7)], "steps", before=1)
    assert [steps.at(x) for x in (0.5, 1.0, 1.5, 2.5)] == [1, 5, 5, 7]
    assert steps.next_integer_change(0.0) == 1.0 and steps.next_integer_change(1.0) == 2.0
    ramp = Profile([(0.0, 0), (2.0, 4)], "ramp")
    assert ramp.at(1.0) == 2 and ramp.at(5) == 4
    assert ramp.next_integer_change(0.0) == pytest.approx(0.25)
    assert ramp.next_integer_change(1.9) is None      # 3.8 rounds to 4, the end value
    assert Profile.constant(3).next_integer_change(0) is None
    # 1.25 s: the value is 2.5 exactly, which round() keeps at 2; the change comes just after
    assert 1.25 < ramp.next_integer_change(1.25) < 1.25 + 1e-12


def test_threshold_crossings():
    """Manual 3.6.13 ("The ADIN lines can be read as digital or analogue inputs at the same time"):
    a digital reading of an analog signal changes only where the signal crosses its threshold,
    both ways, and at a tie just after it (docs/scenarios.md)."""
    tri = Profile([(0.0, 0), (2.0, 1000), (4.0, 0)], "ramp")
    assert tri.next_crossing(0.0, 512) == pytest.approx(1.023)          # up through 511.5
    assert tri.next_crossing(1.5, 512) == pytest.approx(2.977)          # down through 511.5
    assert tri.next_crossing(3.5, 512) is None
    assert tri.next_crossing(0.0, 2000) is None                          # never reaches it
    at_tie = 2 * 511.5 / 1000
    assert at_tie < tri.next_crossing(at_tie, 512) < at_tie + 1e-12
    steps = Profile([(1.0, 300), (2.0, 700), (3.0, 900), (4.0, 100)], "steps")
    assert steps.next_crossing(0.0, 512) == 2.0 and steps.next_crossing(2.0, 512) == 4.0
    assert Profile.constant(600).next_crossing(0.0, 512) is None
