"""The TMC429 core and the PD86-1180 engine behave exactly as recorded before issue 33's rewrite.

Issue 33: "The ramp stays exactly as it is now." tests/motion/tmc429_vectors.json was written by
tests/motion/tmc429_vectors.py from main at 950da38 (before the ramp arithmetic was split from the
engine and the braking walk was rewritten) and checked there against the per-tick oracle
(tests/motion/tmc429_reference.py, TMC4210 datasheet ch. 6.1). Each test here runs the same
recording against the present code and wants every number back: X_ACTUAL, the velocity with its
hidden fraction, AP2 and AP135 (PD86-1180 manual ch. 5) and AP8 at many cycles of each move, the
arrival cycle, `time_at_position` answers and the steps `step_events` lists (TMC4210 6.1.12).
"""
from __future__ import annotations

import json

import pytest

from . import tmc429_vectors as vectors

DATA = json.loads(vectors.OUT.read_text())


def _name(entry: dict) -> str:
    config = ",".join(f"{k}={v}" for k, v in entry["config"].items()) or "defaults"
    moves = ";".join(f"{c[1]}{c[2:]}@{c[0]}" for c in entry["commands"])
    return f"{config}:{moves}"


@pytest.mark.parametrize("entry", DATA["engine"], ids=_name)
def test_pd86_move_is_the_recorded_one(entry):
    """PD86-1180 MVP/MST/ROL (manual 4.6) with AP4/AP5/AP130/AP138/AP153/AP154 settings (ch. 5):
    the recorded samples, arrival, position passes and steps come out again."""
    moves = [tuple(c) for c in entry["commands"]]
    again = json.loads(json.dumps(vectors.record_engine(entry["config"], entry["cap_s"], moves,
                                                        entry["seed"])))
    assert again["arrival"] == entry["arrival"]
    for got, want in zip(again["samples"], entry["samples"], strict=True):
        assert got == want, f"at cycle {want[0]}: [t, AP1, v, AP2, AP135, AP8]"
    assert again["time_at_position"] == entry["time_at_position"]
    assert again["steps"] == entry["steps"]


@pytest.mark.parametrize("entry", DATA["core"], ids=lambda e: str(e["registers"]))
def test_register_script_is_the_recorded_one(entry):
    """TMC4210 6.1 register writes on the bare core (any divisors, PMUL/PDIV, modes, switch
    stops): [now, X_ACTUAL, X_TARGET, velocity, stopping, A_ACTUAL, V_TARGET] after every wait."""
    script = {k: entry[k] for k in ("position_bits", "registers", "actions")}
    assert vectors.record_core(script)["states"] == entry["states"]
