"""Golden values of the six-point and linear ramp engines (TMCM-6212 manual 3.6.4 MVP, 4.1 AP4, AP5,
AP15-AP21; PD28-1021 manual 2.3 AP4/AP5).

Every number below was computed by the engine as it was before its planner was optimised for speed
(bench/run.py bench_6212), so these tests prove that the optimised engine is bit-identical to it:
the same event ticks, the same positions, the same analytic segments. They pin the planner's exact
output, not the manual; the manual's behaviour is tested in test_sixpoint.py and test_linear.py.
The last tests check each fast path against the definition it replaces (braking distance band by
band, planning from scratch instead of the per-distance cache, unit conversion with Fractions).
"""
from __future__ import annotations

import hashlib
import math
import random
from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.motion.linear import LinearRampEngine
from opentmcl.motion.segments import A_PER_PPS2, PSCALE, V_PER_PPS
from opentmcl.motion.sixpoint import (
    Ramp,
    RestPlans,
    SixPointRampEngine,
    acceleration_units,
    plan_position,
    velocity_units,
)

F = 16_000_000
ENGINES = {"six": SixPointRampEngine, "lin": LinearRampEngine}
SIX_NAMES = sorted(SixPointRampEngine.PARAMS)
LIN_NAMES = sorted(LinearRampEngine.PARAMS)


def seg_tuple(s) -> tuple:
    return (s.k0, s.k1, s.p0, s.v0, s.a, s.rest_since)


def run(engine_cls, params: dict, cmds: list, horizon: int = 200 * F, full: bool = False) -> list:
    """Apply timed commands [(tick, name, *args)], stepping through every event in between and for
    `horizon` ticks after the last one; returns the trace of events (and segment lists if `full`)."""
    e = engine_cls(**params)
    trace: list = []
    for t, name, *args in cmds:
        while (n := e.next_event()) is not None and n <= t:
            e.advance(n)
            trace.append(("ev", n, e.position, e.position_reached))
        e.advance(max(t, e.now))
        if name == "configure":
            e.configure(**{args[0]: args[1]})
        else:
            getattr(e, name)(*args)
        if full:
            trace.append(("segs", tuple(seg_tuple(s) for s in e.segments)))
    last = cmds[-1][0] + horizon
    for _ in range(200):
        n = e.next_event()
        if n is None or n > last:
            break
        e.advance(n)
        trace.append(("ev", n, e.position, e.position_reached))
    trace.append(("end", e.now, e.position, e.position_reached, e.velocity))
    return trace


B6 = dict(velocity_v1=20000, acceleration_a1=100000, deceleration_d1=100000, velocity_vstart=100,
          velocity_vstop=200, ramp_wait_time=100)

# (engine, ramp parameters, commands) -> (last event tick, position then, every event tick)
GOLDEN = [
    (("six", {}, [(0, "move_to", 51200)]),
     (31994345, 51200, (16000000, 16000001, 31994345))),
    (("six", {}, [(0, "move_to", -512000)]),
     (175994345, -512000, (16000000, 160000001, 175994345))),
    (("six", {}, [(0, "move_to", 1)]),
     (138331, 1, (70746, 138331))),
    (("six", {}, [(0, "move_to", 7)]),
     (371058, 7, (187096, 371058))),
    (("six", {"max_positioning_speed": 200000, "max_acceleration": 200000},
      [(0, "move_to", 51200), (2 * F, "move_to", 0)]),
     (57351457, 0, (5168686, 25351457, 37168686, 57351457))),
    (("six", {"max_positioning_speed": 56200}, [(0, "move_to", 512000), (12 * F, "move_to", 0)]),
     (355323673, 0, (17562500, 145765125, 163323673, 209562500, 337765125, 355323673))),
    (("six", B6, [(0, "move_to", 204800), (5 * F, "move_to", 0)]),
     (155043326, 0, (3184000, 12934000, 62125485, 71875485, 75043326, 83184000, 92934000, 142125485,
                     151875485, 155043326))),
    (("six", B6, [(0, "move_to", 2**31 - 1000), (F, "move_to", -2**31 + 1000)]),
     (12934000, 33504, (3184000, 12934000))),
    (("six", {}, [(0, "move_to", 100000), (F // 2, "move_to", 200000)]),
     (78494345, 200000, (16000000, 62500001, 78494345))),
    (("six", {}, [(0, "move_to", 100000), (F, "move_to", 30000)]),
     (52582347, 30000, (16000000, 31996875, 42292263, 52582347))),
    (("six", {}, [(0, "move_to", 100000), (F // 3, "configure", "max_positioning_speed", 20000)]),
     (86246466, 100000, (6250000, 80000001, 86246466))),
    (("six", B6, [(0, "move_to", 300000), (3 * F // 2, "configure", "max_deceleration", 3000)]),
     (276149411, 300000, (3184000, 12934000, 190400000, 193568000, 193619200, 196803200, 201019730,
                          272981842, 276149411))),
    (("six", {}, [(0, "rotate", 30000), (F, "move_to", 0)]),
     (49861873, 0, (9375000, 25371875, 37619120, 49861873))),
    (("six", {}, [(0, "move_to", 100000), (F // 2, "set_position", -5), (F, "move_to", 777)]),
     (61659881, 777, (16000000, 31996875, 46832138, 61659881))),
    (("lin", {}, [(0, "move_to", 204800), (5 * F, "move_to", 0)]),
     (159995701, 0, (15999687, 63999688, 79995701, 95999687, 143999688, 159995701))),
    (("lin", {"minimum_speed": 1000, "max_acceleration": 10000}, [(0, "move_to", -12345)]),
     (32498284, -12345, (16249146, 32498284))),
]


@pytest.mark.parametrize(("scenario", "expected"), GOLDEN)
def test_event_ticks_are_unchanged(scenario, expected):
    """MVP (manual 3.6.4) with the ramp of manual 4.1: event ticks and positions as computed before
    the planner was optimised (including on-the-fly target and parameter changes, AP1 overwrite)."""
    kind, params, cmds = scenario
    trace = run(ENGINES[kind], params, cmds)
    evs = tuple(x[1] for x in trace if x[0] == "ev")
    assert (evs[-1], trace[-1][2], evs) == expected


# (scenario index in GOLDEN) -> segment lists (k0, k1, p0, v0, a, rest_since) after each command
GOLDEN_SEGMENTS = {
    0: [((0, 16000000, 0, 0, 107374182400, None),
         (16000000, 16000001, 27487790694400000000000000, 1717986918400000000, 0, None),
         (16000001, 31994345, 27487794130373836800000000, 1717986918400000000, -107374182400, None),
         (31994345, None, 54975581388800000000000000, 0, 0, 31994345))],
    6: [((0, 3184000, 0, 3355443200000000, 209715200000, None),
         (3184000, 12934000, 2147429960908800000000000, 671088640000000000, 107374182400, None),
         (12934000, 62125485, 25440916655308800000000000, 1717986918400000000, 0, None),
         (62125485, 71875485, 194461572108648448000000000, 1717986918400000000, -107374182400, None),
         (71875485, 75043326, 217755058803048448000000000, 671088640000000000, -209715200000, None),
         (75043326, None, 219902325555200000000000000, 0, 0, 75043326)),
        ((80000000, 83184000, 219902325555200000000000000, -3355443200000000, -209715200000, 75043326),
         (83184000, 92934000, 217754895594291200000000000, -671088640000000000, -107374182400, 75043326),
         (92934000, 142125485, 194461408899891200000000000, -1717986918400000000, 0, 75043326),
         (142125485, 151875485, 25440753446551552000000000, -1717986918400000000, 107374182400, 75043326),
         (151875485, 155043326, 2147266752151552000000000, -671088640000000000, 209715200000, 75043326),
         (155043326, None, 0, 0, 0, 155043326))],
    11: [((0, 3184000, 0, 3355443200000000, 209715200000, None),
          (3184000, 12934000, 2147429960908800000000000, 671088640000000000, 107374182400, None),
          (12934000, 91875485, 25440916655308800000000000, 1717986918400000000, 0, None),
          (91875485, 101625485, 296681793753448448000000000, 1717986918400000000, -107374182400, None),
          (101625485, 104793326, 319975280447848448000000000, 671088640000000000, -209715200000, None),
          (104793326, None, 322122547200000000000000000, 0, 0, 104793326)),
         ((24000000, 190400000, 63463403133337600000000000, 1717986918400000000, -6291456000, None),
          (190400000, 193568000, 461005576051097600000000000, 671088640000000000, -209715200000, None),
          (193568000, 193619200, 463152093331456000000000000, 0, 0, 193568000),
          (193619200, 196803200, 463152093331456000000000000, -3355443200000000, -209715200000, 193568000),
          (196803200, 201019730, 461004663370547200000000000, -671088640000000000, -107374182400, 193568000),
          (201019730, 272981842, 453436313567579959459840000, -1123835101315072000, 6291456000, 193568000),
          (272981842, 276149411, 324269810263605720907776000, -671088640000000000, 209715200000, 193568000),
          (276149411, None, 322122547200000000000000000, 0, 0, 276149411))],
}


@pytest.mark.parametrize("index", sorted(GOLDEN_SEGMENTS))
def test_segment_lists_are_unchanged(index):
    """The planned segments of MVP (manual 3.6.4) with A1/V1/D1, VSTART/VSTOP and the ramp wait time
    (manual 4.1 AP15-AP21), exactly as before the optimisation, including a DMAX change on the fly."""
    kind, params, cmds = GOLDEN[index][0]
    trace = run(ENGINES[kind], params, cmds, full=True)
    assert [x[1] for x in trace if x[0] == "segs"] == GOLDEN_SEGMENTS[index]


def random_value(rng: random.Random, name: str) -> int:
    if name == "ramp_wait_time":
        return rng.choice([0, 0, 1, 100, rng.randint(0, 65535)])
    if name == "velocity_v1":
        return rng.choice([0, 0, rng.randint(0, 1_000_000), rng.randint(1, 100000)])
    if name in ("velocity_vstart", "velocity_vstop", "minimum_speed"):
        return rng.choice([0, 10, rng.randint(0, 249999), rng.randint(0, 5000)])
    if name == "max_positioning_speed":
        return rng.choice([51200, rng.randint(1, 7999774), rng.randint(1, 300000)])
    return rng.choice([51200, rng.randint(1, 7629278), rng.randint(1, 400000), rng.randint(0, 5000)])


def random_scenario(rng: random.Random, names: list[str]) -> tuple[dict, list]:
    params = {n: random_value(rng, n) for n in names if rng.random() < 0.8}
    if params.get("max_acceleration") == 0:
        params["max_acceleration"] = 1
    cmds: list = []
    t = 0
    for _ in range(rng.randint(1, 6)):
        t += rng.choice([0, rng.randint(0, F // 10), rng.randint(0, 3 * F)])
        r = rng.random()
        if r < 0.5:
            cmds.append((t, "move_to", rng.choice([rng.randint(-300000, 300000),
                                                   rng.randint(-2**31, 2**31 - 1), rng.randint(-100, 100)])))
        elif r < 0.6:
            cmds.append((t, "rotate", rng.randint(-200000, 200000)))
        elif r < 0.65:
            cmds.append((t, "stop"))
        elif r < 0.7:
            cmds.append((t, "hold", rng.randint(-200000, 200000)))
        elif r < 0.75:
            cmds.append((t, "hard_stop"))
        elif r < 0.92:
            n = rng.choice(names)
            cmds.append((t, "configure", n, random_value(rng, n)))
        else:
            cmds.append((t, "set_position", rng.randint(-2**31, 2**31 - 1)))
    return params, cmds


def digest(kind: str, seed: int, count: int) -> str:
    """SHA-256 over the full traces (segments after every command, every event) of `count` random
    command sequences."""
    names = SIX_NAMES if kind == "six" else LIN_NAMES
    h = hashlib.sha256()
    rng = random.Random(seed)
    for _ in range(count):
        params, cmds = random_scenario(rng, names)
        h.update(repr(run(ENGINES[kind], params, cmds, horizon=20 * F, full=True)).encode())
    return h.hexdigest()


# Issue 29 item 6 changed the "six" digest on purpose (it was eac514bc...196a93): AP21 "waiting time
# after ramping down to zero velocity before next movement or direction inversion can start" (manual
# 4.1) now holds in velocity mode too. Per-scenario hashes before and after: 9 of the 300 sequences
# differ, each one with AP21 > 0 and a ROR/ROL that starts within AP21 of a rest or reverses.
@pytest.mark.parametrize(("kind", "seed", "count", "expected"), [
    ("six", 1, 300, "ba7e28cbcd0a9bc5ad43872dc2824197a6798947b5e7281adae956acd0ebff1a"),
    ("lin", 2, 100, "21ca325699907429b0c78ebe5bff317a1f7063bce4a5a61c7922edc673a4c79f"),
])
def test_random_command_sequences_are_unchanged(kind, seed, count, expected):
    """Random MVP/ROR/MST/AP3/hard stop/AP1/ramp-parameter sequences (manual 3.6.1-3.6.4, 4.1): the
    traces hash to the value computed before the optimisation."""
    assert digest(kind, seed, count) == expected


# --- the fast paths against their definitions ------------------------------------------------------
speeds = st.integers(0, 10**18)
small = st.one_of(st.just(0), st.integers(1, 10**6), st.integers(0, 10**18))


@given(vmax=small, dmax=small, v1=small, d1=small, vstop=small, u=speeds)
def test_braking_closed_form_is_the_band_loop(vmax, dmax, v1, d1, vstop, u):
    """Braking distance from speed u to VSTOP with DMAX above V1 and D1 below (manual 4.1 AP16-AP18,
    AP20): the closed form gives the same (num, den) pair as summing band by band."""
    r = Ramp(vmax=vmax, amax=1, dmax=dmax, v1=v1, a1=1, d1=d1, vstop=vstop)
    for speed in (u, v1, v1 + 1, vstop + 1):
        assert r.braking(speed) == r.braking_loop(speed)


@given(params=st.fixed_dictionaries({
    "max_positioning_speed": st.integers(0, 7999774), "max_acceleration": st.integers(0, 7629278),
    "acceleration_a1": st.integers(0, 7629278), "velocity_v1": st.integers(0, 1_000_000),
    "max_deceleration": st.integers(0, 7629278), "deceleration_d1": st.integers(0, 7629278),
    "velocity_vstart": st.integers(0, 249999), "velocity_vstop": st.integers(0, 249999),
    "ramp_wait_time": st.integers(0, 65535)}),
    t=st.integers(0, 2**40), p=st.integers(-2**31, 2**31), frac=st.integers(0, PSCALE - 1),
    rest=st.one_of(st.none(), st.integers(0, 2**40)), dist=st.integers(-2**32, 2**32))
def test_cached_rest_plans_are_the_direct_plans(params, t, p, frac, rest, dist):
    """MVP from a standstill (manual 3.6.4, ramp wait AP21): the per-distance plan cache returns
    exactly what planning from scratch returns, on first sight, when cached, and from the cache."""
    r = SixPointRampEngine(**params).ramp
    plans = RestPlans(r)
    pos = p * PSCALE + frac
    rest = None if rest is None else min(rest, t)
    target = pos + dist * PSCALE
    direct = plan_position(r, t, pos, 0, rest, target)
    for shift in (0, 0, 12345):  # planned, cached, then reused at another time and place
        moved = plan_position(r, t + shift, pos + shift * PSCALE, 0, None if rest is None else rest + shift,
                              target + shift * PSCALE)
        assert plans.plan(t + shift, pos + shift * PSCALE, None if rest is None else rest + shift,
                          target + shift * PSCALE) == moved
    assert plans.plan(t, pos, rest, target) == direct


@given(x=st.one_of(st.integers(-10**12, 10**12), st.fractions(), st.floats(0, 1e9)))
def test_unit_conversion_is_nearest_engine_unit(x):
    """pps and pps^2 (manual 4.1 AP4/AP5) to engine units: the integer form rounds like the Fraction
    definition floor(x * units + 1/2)."""
    f = Fraction(x)
    assert velocity_units(x) == math.floor(f * V_PER_PPS + Fraction(1, 2))
    assert acceleration_units(x) == math.floor(f * A_PER_PPS2 + Fraction(1, 2))


def back_and_forth(engine_cls, params: dict, base: int, dist: int, idles: list[int],
                   speeds: list[int] | None = None) -> list:
    """MVP base+dist, base, base+dist, ... each once the last one has arrived (after an idle time):
    the repeated distances of a back-and-forth program; with `speeds`, AP4 is set to the next one
    before each move. Returns the trace."""
    e = engine_cls(**params)
    e.set_position(base)
    trace: list = []
    target = base
    for i, idle in enumerate(idles):
        if speeds:
            e.configure(max_positioning_speed=speeds[i % len(speeds)])
        target = base + dist if target == base else base
        e.move_to(((target + 2**31) & 0xFFFF_FFFF) - 2**31)
        trace.append(tuple(seg_tuple(s) for s in e.segments))
        for _ in range(40):
            n = e.next_event()
            if n is None:
                break
            e.advance(n)
            trace.append((n, e.position, e.position_reached, e.velocity))
        e.advance(e.now + idle)
        trace.append((e.now, e.position, e.position_reached))
    return trace


def back_and_forth_digest(kind: str, seed: int, count: int) -> str:
    names = SIX_NAMES if kind == "six" else LIN_NAMES
    h = hashlib.sha256()
    rng = random.Random(seed)
    for _ in range(count):
        params, _ = random_scenario(rng, names)
        dist = rng.choice([rng.randint(-300000, 300000), rng.randint(-50, 50), 51200])
        base = rng.randint(-2**31, 2**31 - 1)
        idles = [rng.choice([0, 0, rng.randint(0, 100000)]) for _ in range(6)]
        speeds = rng.choice([None, [random_value(rng, "max_positioning_speed") for _ in range(rng.randint(1, 3))]])
        h.update(repr(back_and_forth(ENGINES[kind], params, base, dist, idles, speeds)).encode())
    return h.hexdigest()


@pytest.mark.parametrize(("kind", "params", "expected"), [
    ("six", {}, "0b8411595d604360f72afc247ea332e05a3e19a752ee41cefff8e804f4e11f6a"),
    ("six", B6, "6e6b29ec218d3c10735d5a5d4069f25348378fc97a1d853006838e410c578b82"),
    ("lin", {}, "2c32ebf6ce28f395da2b7b6088529d6ee82c300c173972b6eea244fb19ed7806"),
    ("six", {"speeds": [51200, 100000, 51200]}, "ed5091288bc9831f7015067265a5c96fbc6a928ebfbe129b92a5525d4f791931"),
])
def test_repeated_moves_are_unchanged(kind, params, expected):
    """MVP back and forth over the same distance (manual 3.6.4), the ramp wait time (AP21) between
    moves, AP4 switched between moves: the same trace as before the optimisation, also once plans
    are reused."""
    params = dict(params)
    speeds = params.pop("speeds", None)
    trace = back_and_forth(ENGINES[kind], params, 0, 51200, [0, 0, 1000, 0, 7, 0, 0, 0, 0], speeds)
    assert hashlib.sha256(repr(trace).encode()).hexdigest() == expected


@pytest.mark.parametrize(("kind", "seed", "count", "expected"), [
    ("six", 3, 150, "cfe97160e7912aaa2ea7d284ca00fdcee8a1effc2db7ae94a9b4a0dc18fb429e"),
    ("lin", 4, 50, "d5385d6fc6852594e671fad8880c2594c2ea21c953fb2a9026e8a95e72c2cdb3"),
])
def test_random_back_and_forth_is_unchanged(kind, seed, count, expected):
    """Random ramps (manual 4.1), random distances and start positions, six moves back and forth each:
    the traces hash to the value computed before the optimisation."""
    assert back_and_forth_digest(kind, seed, count) == expected
