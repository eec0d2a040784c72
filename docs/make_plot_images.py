"""Regenerate the plot examples in docs/img/ (not a test; docs/plots.md shows them):

    PYTHONPATH=src python docs/make_plot_images.py

One picture per panel kind (plot-position.png, plot-velocity.png, plot-acceleration.png,
plot-load.png, plot-current.png, plot-switches.png), the stallGuard2 homing example
(plot-stallguard.png) and the two runs docs/plots.md walks through (plot-first-program.png,
plot-homing.png). Every run is virtual, so the pictures are the same on
every machine.
"""
from __future__ import annotations

from pathlib import Path

from opentmcl.lang import assemble
from opentmcl.plot import render, run_virtual

ROOT = Path(__file__).resolve().parents[1]
IMG = ROOT / "docs" / "img"
STAGE = ROOT / "examples" / "scenarios" / "tmcm6212_stage.toml"

ORIGIN = """
    SAP 4, 0, 51200        // maximum positioning speed
    SAP 5, 0, 51200        // maximum acceleration
    MVP ABS, 0, 51200
    WAIT POS, 0, 0
    SAP 1, 0, 0            // this point is the origin now
    WAIT TICKS, 0, 50
    MVP ABS, 0, -25600
    WAIT POS, 0, 0
    STOP
"""
LIMIT_STOP = """
    SAP 4, 0, 51200
    SAP 5, 0, 51200
    MVP ABS, 0, 76800      // a trapezoid: up, at speed, down
    WAIT POS, 0, 0
    ROR 0, 30000           // into the right limit switch: a hard stop (AP 26 = 0)
    WAIT TICKS, 0, 150
    STOP
"""
HOMING = """
    SAP 193, 0, 1          // reference search mode 1: left switch
    SAP 194, 0, 51200      // search speed
    SAP 195, 0, 5120       // switch-off speed
    RFS START, 0
    WAIT RFS, 0, 0
    STOP
"""
LOADED = """
    SAP 4, 0, 25600        // through the load steps of the stage (30000: 0.2, 40000: 0.35)
    MVP ABS, 0, 45000
    WAIT POS, 0, 0
    MVP ABS, 0, 0
    WAIT POS, 0, 0
    STOP
"""
COOLSTEP = """
    SAP 172, 0, 2          // coolStep on: lower threshold 2 * 32
    SAP 170, 0, 2          // upper threshold (2 + 2 + 1) * 32
    SAP 171, 0, 1          // current up step 2
    SAP 169, 0, 2          // current down after 2 readings
    SAP 4, 0, 25600
    MVP ABS, 0, 60000
    WAIT POS, 0, 0
    STOP
"""


def _scenario(path: Path) -> dict:
    import tomllib

    return tomllib.loads(path.read_text(encoding="utf-8"))


def _run(source: str, **kw):
    return run_virtual(assemble(source, module="TMCM-6212").instructions, **kw)


def main() -> None:
    homing_world = {"axis": {"0": {"start": 20000, "left": {"position": -30000}}}}
    limit_world = {"axis": {"0": {"right": {"position": 110000}}}}
    coolstep_world = {"axis": {"0": {"load": {"by": "position", "steps": [[20000, 0.45], [40000, 0.1]],
                                              "before": 0.1}}}}
    first = (ROOT / "examples" / "tmcm6212_2.4_first_program.tmc").read_text(encoding="utf-8")
    stallguard = (ROOT / "examples" / "scenarios" / "stallguard_homing.tmc").read_text(encoding="utf-8")
    limit = _run(LIMIT_STOP, scenario=limit_world)
    pictures = {
        "position": (_run(ORIGIN), ["position"], {}),
        "velocity": (limit, ["velocity"], {"phases": True}),
        "acceleration": (limit, ["acceleration"], {}),
        "load": (_run(LOADED, scenario=_scenario(STAGE)), ["position", "load"], {}),
        "stallguard": (_run(stallguard, scenario=_scenario(STAGE)), ["position", "velocity", "load"], {}),
        "current": (_run(COOLSTEP, scenario=coolstep_world), ["load", "current"], {}),
        "switches": (_run(HOMING, scenario=homing_world), ["position", "switches"], {}),
        "first-program": (_run(first), ["position", "velocity", "acceleration"], {"phases": True}),
        "homing": (_run(HOMING, scenario=homing_world), list(("position", "velocity", "switches")), {}),
    }
    for name, (trace, channels, options) in pictures.items():
        out = IMG / f"plot-{name}.png"
        render(trace, out, channels=channels, width=8.0, **options)
        print(f"wrote {out.relative_to(ROOT)} ({len(trace)} samples, {trace.time[-1]:.2f} s)")


if __name__ == "__main__":
    main()
