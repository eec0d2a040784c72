"""Recorded behaviour of the TMC429 core and the PD86-1180 engine (tests/motion/tmc429_vectors.json).

    PYTHONPATH=src python tests/motion/tmc429_vectors.py            # rewrite the JSON file
    PYTHONPATH=src python tests/motion/tmc429_vectors.py --check    # compare, write nothing
    PYTHONPATH=src python tests/motion/tmc429_vectors.py --oracle   # and check with the oracle

The JSON file was written by this script from main at 950da38, before the TMC429 ramp arithmetic
was split from its engine and the braking walk was rewritten for speed (issue 33). It holds, for a
broad set of PD86-1180 moves (AP4, AP5, AP130, AP138, AP153, AP154 settings, MVP of 1 to 200 000
steps, new targets, MST, ROR during a move) and of register scripts on the bare core, the state at
many cycles: X_ACTUAL, the velocity with its hidden fraction, AP2, AP135, AP8, the arrival cycle,
the steps listed by `step_events` (count and digest) and `time_at_position` answers. Every vector
was also checked against the per-tick oracle (tests/motion/tmc429_reference.py) when written,
except the moves marked "oracle": false (too long for it). test_tmc429_vectors.py replays them.

One field was changed by hand since (issue 29 item 1): AP8 of the sample at cycle 8000000 of the
move "RAMP_DIV = PULSE_DIV = 0, AP4 = 2047, AP5 = 100: MVP 100000, MST at 0.5 s" reads 1. That move
has arrived before the MST, so the motor rests on X_TARGET in velocity mode, and AP8 "Indicates that
the actual position equals the target position" (PD86-1180 manual ch. 5) in every ramp mode now;
the oracle does not record AP8, and every other number is the recorded one (`--check` agrees).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import random
import sys
from pathlib import Path
from typing import Any

from opentmcl.motion import CLOCK_HZ
from opentmcl.motion.tmc429 import Tmc429Ramp
from opentmcl.motion.tmc429_engine import Tmc429Engine

HERE = Path(__file__).resolve().parent
OUT = HERE / "tmc429_vectors.json"
SAMPLES = 28
S = CLOCK_HZ

PD86_DEFAULTS = {"max_positioning_speed": 1000, "max_acceleration": 100, "minimum_speed": 1,
                 "ramp_divisor": 7, "pulse_divisor": 3}
"""AP4, AP5, AP130, AP153, AP154 at power-on (src/opentmcl/modules/data/pd86_1180.toml defaults)."""

# settings on top of PD86_DEFAULTS (engine names of the axis parameters)
CONFIGS: list[dict[str, int]] = [
    {},
    {"max_positioning_speed": 2047},
    {"max_acceleration": 10},
    {"max_acceleration": 1000},
    {"max_positioning_speed": 2047, "max_acceleration": 2047},
    {"max_positioning_speed": 2047, "max_acceleration": 200},
    {"max_acceleration": 256},
    {"max_positioning_speed": 300, "max_acceleration": 3},
    {"minimum_speed": 0},
    {"minimum_speed": 40, "max_acceleration": 50},
    {"ramp_mode": 1},
    {"ramp_divisor": 3, "pulse_divisor": 5, "max_acceleration": 100},
    {"ramp_divisor": 0, "pulse_divisor": 0, "max_positioning_speed": 2047, "max_acceleration": 100},
    {"ramp_divisor": 5, "pulse_divisor": 5, "max_acceleration": 30},
    {"ramp_divisor": 9, "pulse_divisor": 2, "max_acceleration": 400},
]
MOVES: list[tuple[int, list[tuple]]] = [     # (seconds at most, commands)
    (60, [(0, "move_to", 5_000)]),
    (60, [(0, "move_to", 20_000)]),
    (60, [(0, "move_to", 200_000)]),
    (60, [(0, "move_to", -37)]),
    (60, [(0, "move_to", 1)]),
    (60, [(0, "move_to", 50_000), (S // 3, "move_to", 10_000)]),     # new target while moving
    (60, [(0, "move_to", 30_000), (S // 4, "move_to", -3_000)]),     # the other way round
    (60, [(0, "move_to", 100_000), (S // 2, "stop")]),               # MST
    (1, [(0, "move_to", 100_000), (S // 5, "rotate", -500)]),        # ROL while moving
]
ORACLE_ITERATIONS = 600_000
"""Moves the per-tick oracle walks in fewer clock ticks than this are checked against it."""


def _digest(steps: list[tuple[int, int]]) -> str:
    return hashlib.sha256(repr(steps).encode()).hexdigest()[:16]


def _apply(e: Tmc429Engine, cmd: tuple) -> None:
    _t, name, *args = cmd
    getattr(e, name)(*args)


def _fresh(config: dict[str, int]) -> Tmc429Engine:
    e = Tmc429Engine()
    e.configure(**{**PD86_DEFAULTS, **config})
    return e


def _arrival(config: dict[str, int], moves: list[tuple], cap: int) -> int:
    """Cycle at which the motion after the last command comes to rest (or `cap`), event by event."""
    e = _fresh(config)
    for cmd in moves:
        while (t := e.next_event()) is not None and t <= cmd[0]:
            e.advance(t)
        e.advance(cmd[0])
        _apply(e, cmd)
    while (t := e.next_event()) is not None and t <= cap:
        e.advance(t)
        if e.position_reached or (moves[-1][1] == "stop" and not e.moving):
            return e.now
    return cap if t is not None else e.now


def sample_ticks(end: int, seed: int) -> list[int]:
    """About SAMPLES cycles: evenly spread over 0..end, a few random ones and the last cycles
    before end."""
    rnd = random.Random(seed)
    ticks = {end * k // (SAMPLES - 11) for k in range(1, SAMPLES - 11)}
    ticks |= {rnd.randrange(1, end + 2) for _ in range(6)}
    ticks |= {max(1, end - d) for d in (0, 1, 31, 32, 33, 4096)}
    return sorted(ticks)


def engine_row(e: Tmc429Engine) -> list[int]:
    r = e.ramp
    return [e.now, e.position, r.v_internal, e.target_velocity, e.actual_acceleration,
            int(e.position_reached)]


def _commanded(config: dict[str, int], moves: list[tuple]) -> Tmc429Engine:
    e = _fresh(config)
    for cmd in moves:
        e.advance(cmd[0])
        _apply(e, cmd)
    return e


def step_windows(moves: list[tuple], end: int) -> list[tuple[int, int]]:
    """(from, to) cycles whose steps are listed: up to the last command, then the first and the
    last twentieth of the motion after it."""
    last = moves[-1][0]
    part = (end - last) // 20
    return [(0, last), (last, last + part), (end - part, end)]


def _listed_steps(config: dict[str, int], moves: list[tuple], end: int) -> list[tuple[int, int]]:
    e = _fresh(config)
    pending = list(moves)
    listed: list[tuple[int, int]] = []
    for start, stop in step_windows(moves, end):
        e.advance(max(start, e.now))
        while pending and pending[0][0] <= stop:
            listed += e.ramp.step_events(pending[0][0])
            _apply(e, pending.pop(0))
        listed += e.ramp.step_events(max(stop, e.now))
    return listed


def record_engine(config: dict[str, int], cap_s: int, moves: list[tuple], seed: int) -> dict[str, Any]:
    end = _arrival(config, moves, cap_s * S)
    ticks = sample_ticks(end, seed)
    e = _fresh(config)
    pending = list(moves)
    rows = []
    for t in ticks:
        while pending and pending[0][0] <= t:
            e.advance(pending[0][0])
            _apply(e, pending.pop(0))
        e.advance(t)
        rows.append(engine_row(e))
    target = moves[-1][2] if moves[-1][1] == "move_to" else None
    positions = [p for p in (1, 7, 1000, 4321, -5, target and target // 2, target) if p is not None]
    probe = _commanded(config, moves)
    passes = {str(p): probe.time_at_position(p) for p in positions}
    listed = _listed_steps(config, moves, end)
    period = 32 << min(e.ramp.ramp_div, e.ramp.pulse_div)
    return {"config": config, "commands": [list(c) for c in moves], "cap_s": cap_s, "seed": seed,
            "arrival": end, "samples": rows,
            "time_at_position": passes, "steps": [len(listed), _digest(listed)],
            "oracle": end // period < ORACLE_ITERATIONS}


# --- the bare core: register scripts -----------------------------------------------------------
def _script(rnd: random.Random) -> dict[str, Any]:
    regs = {"pulse_div": rnd.randint(0, 7), "ramp_div": rnd.randint(0, 9),
            "v_max": rnd.choice([rnd.randint(1, 2047), rnd.randint(1, 80)]),
            "v_min": rnd.randint(0, 6), "a_max": rnd.choice([rnd.randint(1, 2047), rnd.randint(1, 60)]),
            "pmul": rnd.randint(128, 255), "pdiv": rnd.randint(0, 13),
            "mode": rnd.choice([0, 0, 0, 1, 2, 3])}
    actions = []
    for _ in range(rnd.randint(1, 5)):
        kind = rnd.randrange(9)
        if kind < 4:
            action: Any = {"x_target": rnd.randint(-60_000, 60_000)}
        elif kind == 4:
            action = {"v_target": rnd.randint(-2047, 2047)}
        elif kind == 5:
            action = {"mode": rnd.randint(0, 3)}
        elif kind == 6:
            action = {"v_actual": rnd.randint(-2047, 2047)}
        elif kind == 7:
            action = {"a_max": rnd.randint(1, 2047)}
        else:
            action = rnd.choice(["hard_stop", "soft_stop"])
        waits = [rnd.randint(1, 40_000) * 32 for _ in range(rnd.randint(1, 5))]
        actions.append([action, waits])
    return {"position_bits": rnd.choice([24, 32]), "registers": regs, "actions": actions}


def core_row(r: Any) -> list[int]:
    return [r.now, r.x_actual, r.x_target, r.v_internal, int(r.stopping), r.a_actual, r.v_target]


def apply_core(r: Any, action: Any) -> None:
    if action == "hard_stop":
        r.stop(soft=False)
    elif action == "soft_stop":
        r.stop(soft=True)
    else:
        r.set(**action)


def record_core(script: dict[str, Any]) -> dict[str, Any]:
    r = Tmc429Ramp(position_bits=script["position_bits"])
    r.set(**script["registers"])
    rows = []
    for action, waits in script["actions"]:
        apply_core(r, action)
        for w in waits:
            r.advance(r.now + w)
            rows.append(core_row(r))
    return {**script, "states": rows}


# --- the oracle -----------------------------------------------------------------------------
MIRRORED = ("x_target", "v_min", "v_max", "a_max", "pmul", "pdiv", "pulse_div", "ramp_div", "mode",
            "v_target")


def _mirror(e: Tmc429Engine, ref: Any) -> None:
    """Write the engine's registers that differ into the per-tick model."""
    r = e.ramp
    regs = {name: getattr(r, name) for name in MIRRORED if getattr(r, name) != getattr(ref, name)}
    if r.mode not in (2, 3):
        regs.pop("v_target", None)            # computed by the chip in ramp_mode / soft_mode
    ref.set(**regs)


def _s32(x: int) -> int:
    return (x + 2**31) % 2**32 - 2**31


def check_engine_with_oracle(entry: dict[str, Any]) -> None:
    """The per-tick model, given the engine's register writes, has the recorded X_ACTUAL and
    velocity at every sample, arrives on the recorded cycle and makes the recorded steps."""
    sys.path.insert(0, str(HERE))
    from tmc429_reference import ReferenceRamp

    class Recording(ReferenceRamp):
        def on_step(self, cycle: int, direction: int) -> None:
            self.steps.append((cycle, direction))

    e, ref = _fresh(entry["config"]), Recording(position_bits=32)
    ref.steps = []
    _mirror(e, ref)
    pending = [tuple(c) for c in entry["commands"]]
    for row in entry["samples"]:
        t = row[0]
        while pending and pending[0][0] <= t:
            cmd = pending.pop(0)
            e.advance(cmd[0])
            ref.advance(cmd[0])
            _apply(e, cmd)
            _mirror(e, ref)
        ref.advance(t)
        if [_s32(ref.x_actual), ref.v] != row[1:3]:
            raise AssertionError(f"oracle differs at {t}: {entry['config']} {entry['commands']}")
    end = entry["arrival"]
    ref.advance(end)
    windows = step_windows([tuple(c) for c in entry["commands"]], end)
    listed = [s for s in ref.steps if any(a < s[0] <= b for a, b in windows)]
    count, digest = entry["steps"]
    if (len(listed), _digest(listed)) != (count, digest):
        raise AssertionError(f"oracle steps differ: {entry['config']} {entry['commands']}")


def check_core_with_oracle(entry: dict[str, Any]) -> None:
    """The per-tick model run through the same register script has the recorded X_ACTUAL,
    X_TARGET, velocity and soft-stop state after every wait."""
    sys.path.insert(0, str(HERE))
    from tmc429_reference import ReferenceRamp

    ref = ReferenceRamp(position_bits=entry["position_bits"])
    ref.set(**entry["registers"])
    rows = iter(entry["states"])
    for action, waits in entry["actions"]:
        apply_core(ref, action)
        for w in waits:
            ref.advance(ref.now + w)
            row = next(rows)
            if [ref.now, ref.x_actual, ref.x_target, ref.v, int(ref.stopping)] != row[:5]:
                raise AssertionError(f"oracle differs at {ref.now}: {entry['registers']}")


def build() -> dict[str, Any]:
    engine = []
    seed = 0
    for config in CONFIGS:
        for cap_s, moves in MOVES:
            seed += 1
            engine.append(record_engine(config, cap_s, moves, seed))
    rnd = random.Random(33)
    core = [record_core(_script(rnd)) for _ in range(60)]
    return {"about": "tests/motion/tmc429_vectors.py", "engine": engine, "core": core}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="compare with the file, write nothing")
    ap.add_argument("--oracle", action="store_true", help="also check every vector with the oracle")
    args = ap.parse_args()
    data = json.loads(json.dumps(build()))
    if args.oracle:
        for entry in data["engine"]:
            if entry["oracle"]:
                check_engine_with_oracle(entry)
        for entry in data["core"]:
            check_core_with_oracle(entry)
        print("the per-tick oracle agrees with every vector marked oracle")
    if args.check:
        same = data == json.loads(OUT.read_text())
        print("same as the recorded vectors" if same else "DIFFERENT from the recorded vectors")
        return 0 if same else 1
    OUT.write_text(json.dumps(data, separators=(",", ":")) + "\n")
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
