"""A trace sample is what GAP answers at that instant, and changes nothing the next `advance` does
(issue 33, "Speed where users are": "`Trace.sample` of six axes ... Measure it against the 54 GAP
reads it stands for (`vm.request`)"; the brief: "Values must stay exactly what GAP answers at that
instant ... A sample must not change what the next `advance` does").

Each module runs its example scenario (examples/scenarios/: switches, hard stops, loads over
position and over time, an encoder) with moves that cross the switches, push into a hard stop
(steps are lost, the deviation limit AP212 stops the motor), rotate a circular axis through its
home switch, write the encoder (AP209) and run coolStep (AP172). Twin modules get the same commands
at the same ticks: one is sampled (`Trace.sample`), the other read through `vm.request(6, n, a)`
(TMCM-6212 manual 3.6.6 GAP) and `world.axis(a).physical_position`; a third is not looked at.
Samples fall between the world's events (the interval is 13 ms).
"""
from __future__ import annotations

from pathlib import Path

import pytest

from opentmcl import VirtualModule
from opentmcl.trace import CHANNELS, WORLD_CHANNELS, Trace

SCENARIOS = Path(__file__).resolve().parents[2] / "examples" / "scenarios"
SAP, GAP, ROR, MST, MVP = 5, 6, 1, 3, 4
STEP = 0.013
STEPS = 480

# step -> commands (command, type, motor, value), TMCM-6212 manual 3.6
MOVES: dict[str, dict[int, list[tuple[int, int, int, int]]]] = {
    "TMCM-6212": {
        0: [(SAP, 12, 0, 1), (SAP, 13, 0, 1),          # limit switches do not stop: on to the hard stops
            (SAP, 4, 0, 60000), (MVP, 0, 0, 90000),    # home 10000, loads 30000/40000, right 50000, end 60000
            (ROR, 0, 1, 30000),                        # the rotary table through its home switch
            (SAP, 172, 2, 1), (SAP, 182, 2, 1000), (SAP, 4, 2, 50000), (MVP, 0, 2, 300000),   # coolStep
            (SAP, 4, 3, 20000), (SAP, 212, 3, 5000), (MVP, 0, 3, -100000),   # deviation limit AP212
            (ROR, 0, 4, -15000), (MVP, 0, 5, 2000)],
        90: [(SAP, 209, 0, 1234), (MST, 0, 4, 0)],      # an encoder write; a stop
        200: [(MVP, 0, 0, -90000), (SAP, 209, 3, -50)],  # back through every switch to the other end;
        300: [(SAP, 1, 1, 0), (MVP, 0, 4, 4000)],         # the encoder jumps: a deviation stop; a new origin
    },
    "TMCM-1180": {
        0: [(SAP, 12, 0, 1), (SAP, 4, 0, 1500), (SAP, 5, 0, 2047), (MVP, 0, 0, 40000)],   # right 25000, end 30000
        150: [(SAP, 12, 0, 0), (SAP, 209, 0, 77), (MVP, 0, 0, -40000)],  # home 2000 (and REFL), left -25000
        330: [(ROR, 0, 0, 600)],
    },
    "TMCM-1021": {
        0: [(SAP, 4, 0, 60000), (SAP, 5, 0, 100000), (MVP, 0, 0, 60000)],   # the right switch (40000) stops it
        120: [(MVP, 0, 0, -60000)],                     # home -10000, left -40000
        330: [(SAP, 13, 0, 1), (MVP, 0, 0, -60000)],    # the left switch no longer stops it
    },
}
FILES = {"TMCM-6212": "tmcm6212_stage.toml", "TMCM-1180": "pd86_1180_three_switch.toml",
         "TMCM-1021": "pd28_1021_home.toml"}


def module(name: str) -> VirtualModule:
    return VirtualModule(name, scenario=SCENARIOS / FILES[name])


def command(vm: VirtualModule, step: int, name: str) -> None:
    for cmd, type_, motor, value in MOVES[name].get(step, []):
        reply = vm.request(cmd, type_, motor, value)
        assert reply is not None and reply.status == 100, (cmd, type_, motor, value)


def gap_row(vm: VirtualModule) -> list[int | None]:
    """What GAP answers now (None: status other than 100), and the stage, in the trace's order."""
    out: list[int | None] = []
    for a in range(len(vm.axes)):
        for ch in WORLD_CHANNELS:
            number = CHANNELS[ch][0]
            if number is None:
                out.append(vm.world.axis(a).physical_position)
                continue
            reply = vm.request(GAP, number, a)
            assert reply is not None
            out.append(reply.value if reply.status == 100 else None)
    return out


def motion(vm: VirtualModule) -> list[object]:
    """What the next advance works on and what it produced, read without reading through the world."""
    state: list[object] = [vm.now, vm.flags, vm.drain_events()]
    for axis in vm.axes:
        e = axis.engine
        state += [e.position, e.velocity, e.target_position, e.mode, axis.error_flags]
    return state


@pytest.mark.parametrize("name", sorted(MOVES))
def test_every_sampled_value_is_what_gap_answers_at_that_tick(name):
    sampled, asked = module(name), module(name)
    trace = Trace()
    answers = []
    for step in range(STEPS):
        command(sampled, step, name)
        command(asked, step, name)
        sampled.advance(STEP)
        asked.advance(STEP)
        trace.sample(sampled)
        answers.append([round(asked.time, 9), *gap_row(asked)])
    rows = trace.rows                     # read once at the end: the samples went into the columns in blocks
    assert len(rows) == STEPS
    for step, (row, answer) in enumerate(zip(rows, answers, strict=True)):
        assert list(row.values()) == answer, (name, step)
    for a in range(len(sampled.axes)):
        assert any(r[f"vel{a}"] for r in rows), (name, a)          # every axis moved
    seen = {ch: {r[f"{ch}0"] for r in rows} for ch in ("left", "right", "home")}
    assert all(states == {0, 1} for states in seen.values()), (name, seen)   # axis 0 crossed every switch


@pytest.mark.parametrize("name", sorted(MOVES))
def test_a_traced_run_equals_an_untraced_one_state_by_state(name):
    traced, untraced = module(name), module(name)
    trace = Trace()
    for step in range(STEPS):
        command(traced, step, name)
        command(untraced, step, name)
        traced.advance(STEP)
        untraced.advance(STEP)
        trace.sample(traced)
        assert motion(traced) == motion(untraced), (name, step)
    # what the world did on the way (switch stops, lost steps, deviation, encoder): the same answers
    # of the switches, the encoder, the stage and the rest. Not AP180/AP206: a read, GAP's as a
    # sample's, brings the current model to now (the standby timer of an axis without world events
    # starts at the first read after it stopped, coolStep regulates at each read), so a run that was
    # read differs there from one that was not (docs/assumptions.md "What a sample reads").
    for a in range(len(traced.axes)):
        for number in (1, 3, 8, 9, 10, 11, 29, 207, 209):
            assert traced.request(GAP, number, a) == untraced.request(GAP, number, a), (name, a, number)
        assert traced.world.axis(a).physical_position == untraced.world.axis(a).physical_position


def test_a_sample_that_ends_a_step_loss_tells_the_scheduler_as_gap_does():
    """docs/world.md "Load, current, stallGuard2, coolStep": steps are lost while the load exceeds
    what the motor can make at its speed; the stage stands while the counter runs on. Stopping (MST,
    TMCM-6212 manual 3.6.3) lowers the speed, and a read once the motor is strong enough again lets
    the stage follow the counter (`Rotor.follow`), here into the right limit switch (AP12 = 0: it
    stops the motor). GAP's world reads are writes for the scheduler (firmware/table.py); a sample
    that ends a step loss says so too, so the sampled module stops at the switch like the one read
    through GAP, not at its next event."""
    scenario = {"module": "TMCM-6212", "axis": {"0": {"load": 0.5, "torque_falloff_speed": 100000,
                                                      "right": {"position": 200000}}}}
    sampled, asked = (VirtualModule("TMCM-6212", scenario=scenario) for _ in range(2))
    for vm in (sampled, asked):
        for number, value in ((6, 255), (4, 80000), (5, 20000), (17, 20000)):   # capacity 1 - v / 100000
            vm.request(SAP, number, 0, value)
        vm.request(MVP, 0, 0, 10**6)      # the load 0.5 is too much above 50000 pps
    trace = Trace(axes=[0])
    for step in range(800):
        if step == 400:                   # at full speed since 4 s, the stage standing at 160000
            assert sampled.world.axis(0).rotor.slipping == 1 and trace.rows[-1]["stage0"] == 160000
            for vm in (sampled, asked):
                vm.request(MST, 0, 0, 0)
        for vm in (sampled, asked):
            vm.advance(STEP)
        trace.sample(sampled)
        row = trace.rows[-1]
        assert [row[f"{ch}0"] for ch in ("pos", "vel", "left", "right", "home", "load", "current", "encoder",
                                         "stage")] == gap_row(asked)[:9], step
        assert motion(sampled) == motion(asked), step
    assert trace.rows[-1]["stage0"] == 200000 and trace.rows[-1]["right0"] == 1


def test_the_sample_follows_a_power_cycle():
    """A power cycle (`VirtualModule.power_up`) makes new axes with the counter at 0, while the
    world and its stage stay (docs/world.md): the trace reads the new axes."""
    vm = module("TMCM-6212")
    trace = Trace(axes=[0])
    command(vm, 0, "TMCM-6212")
    vm.advance(0.5)
    trace.sample(vm)
    moved = trace.rows[-1]["pos0"]
    assert moved and moved == vm.request(GAP, 1, 0).value
    vm.power_up()
    vm.advance(0.1)
    trace.sample(vm)
    assert trace.rows[-1]["pos0"] == vm.request(GAP, 1, 0).value == 0
    assert trace.rows[-1]["stage0"] == vm.world.axis(0).physical_position == moved
