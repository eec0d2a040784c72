"""The carried next-event limit (docs/architecture.md "Time"; docs/performance.md "Round 24"): after
an `advance` whose limit still holds, a host that only sends pre-bound reads (GAP, GGP, GIO answered
without the general path) lets the next `advance` skip its event loop up to that limit. Everything
else makes the next `advance` start afresh. The result must be exactly the reference's, which looks
every event up afresh (the oracle, oracle.py): positions, velocities, the segment plans (their rest
instants too), heartbeats, timers, the world and every reply.

TMCM-6212 manual 3.6.6 (GAP 1 actual position, 3 actual speed, 8 position reached, 10/11 the switch
states), 3.6.1-3.6.4 (ROR, MST, MVP), 3.6.9 (SGP; GP68 "Serial heartbeat ... the motor will be
stopped" when no command came for that many ms), 3.5.6.4 and bank 3 (timer periods)."""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from opentmcl import VirtualModule
from opentmcl.lang.assembler import assemble
from opentmcl.motion import CLOCK_HZ
from opentmcl.motion.stage import Profile
from opentmcl.protocol.frame import Request

from .oracle import ReferenceModule

MS = CLOCK_HZ // 1000


def frame(command: int, type_: int = 0, motor: int = 0, value: int = 0) -> bytes:
    return Request(1, command, type_, motor, value).encode()


def pair(scenario: dict | None = None) -> tuple[VirtualModule, VirtualModule]:
    fast = VirtualModule("TMCM-6212", address=1, scenario=scenario)
    ref = ReferenceModule("TMCM-6212", address=1, scenario=scenario)
    return fast, ref


def state(vm: VirtualModule) -> tuple:
    """What a run can differ in, read without commands (a command would end the carry)."""
    engines = tuple((e.now, e.position, e.velocity, tuple(tuple(p) for p in e._queue.pieces))
                    for e in (ax.engine for ax in vm.axes))
    world = tuple((aw.rotor.phys, aw.rotor.offset, aw.rotor.slipping, tuple(aw.switches.raw.values()))
                  for aw in vm.world.axes_world)
    ints = vm.interrupts
    return (vm.now, vm.heartbeats.fired, dict(vm.heartbeats.last), engines, world, tuple(ints._due),
            tuple(sorted(ints.pending)), tuple(ax.error_flags for ax in vm.axes), tuple(vm.drain_events()))


def loop_lookups(vm: VirtualModule) -> list[int]:
    """Count the event look-ups of `vm` (each pass of `advance_to`'s loop makes one)."""
    calls = [0]
    inner = vm.scheduler._next_event

    def counted(until: int) -> int:
        calls[0] += 1
        return inner(until)
    vm.scheduler._next_event = counted  # type: ignore[method-assign]
    return calls


POLL = [frame(6, 1, a) for a in range(3)] + [frame(6, 8, a) for a in range(3)]


def poll(vm: VirtualModule) -> list[bytes]:
    return [vm.handle(f) for f in POLL]


def moving(scenario: dict | None = None) -> tuple[VirtualModule, VirtualModule]:
    """Axes 0-2 on their way to far targets at different speeds (SAP 4, MVP ABS), both modules
    advanced past the acceleration (AP5 default) and polled once, so that their reads are bound."""
    fast, ref = pair(scenario)
    for vm in (fast, ref):
        for a in range(3):
            vm.handle(frame(5, 4, a, 700 + 400 * a))
            vm.handle(frame(4, 0, a, 1_000_000))
        vm.advance(1.0)
        poll(vm)
        vm.advance(0.01)
    return fast, ref


def run_polls(fast: VirtualModule, ref: VirtualModule, n: int, dt: float = 0.01) -> None:
    for _ in range(n):
        for vm in (fast, ref):
            vm.advance(dt)
        assert poll(fast) == poll(ref)
        assert state(fast) == state(ref)


def test_a_polling_host_skips_the_event_loop():
    """Axes cruising to far targets: nothing happens between two polls, and with only pre-bound
    reads in between no `advance` looks the next event up again; every reply and the state still
    equal the reference's, which looks up at every `advance`."""
    fast, ref = moving()
    calls, ref_calls = loop_lookups(fast), loop_lookups(ref)
    run_polls(fast, ref, 50)
    assert calls[0] == 0
    assert ref_calls[0] == 50
    assert fast.axes[0].engine.velocity != 0  # still cruising: the scenario had no event to take


def test_the_carry_ends_at_the_limit():
    """The limit is the engines' next event: MVP ABS 6000 at 700 pps arrives within 10 s; the
    polls up to it are carried, the one that reaches it runs the loop and reports GAP 8 = 1 at
    the same poll as the reference."""
    fast, ref = pair()
    for vm in (fast, ref):
        vm.handle(frame(5, 4, 0, 700))
        vm.handle(frame(4, 0, 0, 6000))
        vm.advance(0.01)
        poll(vm)
    calls = loop_lookups(fast)
    reached = None
    for i in range(1000):
        for vm in (fast, ref):
            vm.advance(0.01)
        got = poll(fast)
        assert got == poll(ref)
        assert state(fast) == state(ref)
        if got[3][7] == 1 and reached is None:  # GAP 8 of axis 0: the value's low byte
            reached = i
            break
    assert reached is not None
    assert 0 < calls[0] < reached  # the loop ran only around the ramp's events


def test_a_command_ends_the_carry():
    """MST (3.6.3) between two polls: the next `advance` looks its events up afresh and the motor
    decelerates as in the reference."""
    fast, ref = moving()
    for vm in (fast, ref):
        vm.handle(frame(3, 0, 1))
    calls = loop_lookups(fast)
    run_polls(fast, ref, 5)
    assert calls[0] > 0


@pytest.mark.parametrize("bound", [False, True])
def test_a_faster_speed_written_during_a_move_brings_the_arrival_forward(bound):
    """TMCM-6212 4.1 AP4 "maximum positioning speed" written during a move (3.6.5 SAP, on the general
    path or answered by the pre-bound setter) speeds the move up, and the arrival is reported
    (3.6.35, command 138) at the new, earlier tick, as in the reference: a command table that
    under-declares SAP's effect (issue 33: "Whoever adds a command gives its effect in the table")
    leaves the engines' next events stale, and the product then reports at the old tick."""
    fast, ref = pair()
    for vm in (fast, ref):
        vm.handle(frame(5, 4, 0, 1000))  # the frame's shape is bound from now on
        vm.handle(frame(138, 0, 0, 1))
        vm.handle(frame(4, 0, 0, 20000))  # 20 s at 1000 pps, under 1 s at 50000
        vm.advance(0.5)
        vm.next_event_in()
        if not bound:
            vm.forget_requests()
        assert vm.is_prebound(frame(5, 4, 0, 50000)) == bound
        vm.handle(frame(5, 4, 0, 50000))
        vm.advance(3.0)
    got = state(fast)
    assert got == state(ref)
    assert len(got[-1]) == 1 and got[3][0][1] == 20000  # arrived within the 3 s, event sent


def test_a_general_read_ends_the_carry():
    """A read the general path answers (GAP 207 clears the flags it reads) may be followed by
    anything: the next `advance` starts afresh."""
    fast, ref = moving()
    for vm in (fast, ref):
        vm.handle(frame(6, 207, 0))
    calls = loop_lookups(fast)
    run_polls(fast, ref, 1)
    assert calls[0] == 1


def test_a_heartbeat_restarted_by_reads_still_fires():
    """GP68 = 50 ms: the pre-bound reads restart the serial heartbeat, so the motors run on while
    the host polls every 10 ms; 50 ms after the last read the heartbeat stops them, at the same
    tick as in the reference, also after it had fired once and a read restarted it."""
    fast, ref = moving()
    for vm in (fast, ref):
        vm.handle(frame(9, 68, 0, 50))
    run_polls(fast, ref, 20)
    assert fast.axes[0].engine.velocity != 0
    for _ in range(8):  # no reads: it fires 50 ms after the last one
        for vm in (fast, ref):
            vm.advance(0.01)
        assert state(fast) == state(ref)
    assert fast.heartbeats.fired and fast.axes[0].engine.velocity == 0
    run_polls(fast, ref, 3)  # reads restart it: it fires again 50 ms later (a new rest instant)
    for _ in range(8):
        for vm in (fast, ref):
            vm.advance(0.01)
        assert state(fast) == state(ref)
    assert fast.heartbeats.fired


def test_a_world_input_set_between_polls_ends_the_carry():
    """`World.set_input` gives the world a new next input change: the next `advance` looks it up."""
    fast, ref = moving()
    calls = loop_lookups(fast)
    for vm in (fast, ref):
        vm.world.set_input(0, 0, Profile([(0.5, 1.0)]))
    run_polls(fast, ref, 2)
    assert calls[0] >= 1


def test_a_switch_forced_between_polls_stops_the_motor():
    """A left switch forced active (`AxisWorld.force_switch`) while axis 1 runs left (ROL,
    3.6.2): the limit switch stops it (3.6.6 AP12 = 0 enables it) at the same tick as in the
    reference, although the polls before were carried."""
    fast, ref = moving()
    for vm in (fast, ref):
        vm.handle(frame(2, 0, 1, 500))
    run_polls(fast, ref, 3)
    for vm in (fast, ref):
        vm.world.axis(1).force_switch("left", 1)
    run_polls(fast, ref, 5)
    assert fast.axes[1].engine.velocity == 0


def test_a_running_program_is_never_carried():
    """A program (3.6.36 download, 129 run) runs at its own ticks, which are not in the limit: no
    `advance` is carried while it runs, even when its instructions are all pure (CALC, JA: no
    write that would end the limit), and the accumulator counts as in the reference."""
    fast, ref = moving()
    for vm in (fast, ref):
        vm.handle(frame(132))
        for ins in assemble("Loop: CALC ADD, 1\nJA Loop", module="TMCM-6212").instructions:
            vm.handle(frame(*ins))
        vm.handle(frame(133))
        vm.handle(frame(129))
    calls = loop_lookups(fast)
    run_polls(fast, ref, 5)
    assert calls[0] >= 5
    assert fast.accumulator == ref.accumulator > 100


def test_a_load_set_between_polls_ends_the_carry():
    """`AxisWorld.set_load` puts an overload 300 microsteps ahead of axis 0 (a load by position
    above the holding capacity: steps are lost from there, docs/world.md): the polls after it must
    find that event, as the reference does, although the polls before were carried."""
    fast, ref = moving()
    ahead = fast.axes[0].engine.position + 300
    assert ahead == ref.axes[0].engine.position + 300
    for vm in (fast, ref):
        vm.world.axis(0).set_load(Profile([(ahead, 5.0)]), by="position")
    run_polls(fast, ref, 100)
    assert fast.world.axis(0).rotor.slipping


def test_a_world_acting_at_every_tick_is_not_carried():
    """A load over time on an axis that needs events is evaluated at every tick the module stops
    at (`World.quiet` False), also long before its next step: no `advance` is carried."""
    fast, ref = moving({"axis": {"0": {"load": {"by": "time", "steps": [[100, 0.5]]},
                                       "left": {"position": -100_000}}}})
    calls = loop_lookups(fast)
    run_polls(fast, ref, 5)
    assert calls[0] >= 5


SCENARIOS = [
    None,
    {"axis": {"0": {"left": {"position": -1500}, "right": {"position": 2500}}}},
    {"axis": {"1": {"load": {"by": "time", "ramp": [[0, 0.0], [0.4, 0.9]]}}}},
    {"axis": {"0": {"load": {"by": "position", "steps": [[900, 0.95]]}}},
     "input": [{"bank": 0, "port": 0, "steps": [[0.05, 1], [0.12, 0]]}]},
]
READS = st.sampled_from([frame(6, 1, 0), frame(6, 1, 1), frame(6, 8, 0), frame(6, 3, 1), frame(6, 11, 0),
                         frame(6, 10, 0), frame(10, 68, 0), frame(15, 0, 0), frame(6, 4, 1)])
COMMANDS = st.sampled_from([frame(1, 0, 0, 800), frame(2, 0, 1, 600), frame(3, 0, 0), frame(4, 0, 1, -900),
                            frame(4, 1, 0, 300), frame(5, 4, 0, 1200), frame(5, 181, 1, 300),
                            frame(9, 68, 0, 30), frame(9, 68, 0, 0), frame(9, 0, 3, 7), frame(6, 207, 0)])
STEP = st.one_of(
    st.tuples(st.just("advance"), st.integers(0, 400)),  # in 0.1 ms
    st.tuples(st.just("read"), READS),
    st.tuples(st.just("command"), COMMANDS),
    st.tuples(st.just("switch"), st.sampled_from([("left", 1), ("left", None), ("right", 1), ("right", None)])),
)


@settings(max_examples=80, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(range(len(SCENARIOS))), st.lists(STEP, min_size=5, max_size=40))
def test_carried_runs_equal_the_reference(scenario, steps):
    """Random hosts: reads, commands, forced switches and advances in any order, on worlds with
    switches, loads by time and position and an input signal; the carried module and the
    reference give the same replies and states."""
    fast, ref = pair(SCENARIOS[scenario])
    for kind, arg in steps:
        if kind == "advance":
            for vm in (fast, ref):
                vm.advance(arg / 10_000)
        elif kind == "switch":
            for vm in (fast, ref):
                vm.world.axis(0).force_switch(*arg)
        else:
            assert fast.handle(arg) == ref.handle(arg), (kind, arg)
        assert state(fast) == state(ref), (kind, arg)
