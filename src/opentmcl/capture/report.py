"""Replay reports for CI and for people: JSON, JUnit XML (here) and HTML (capture/html.py).

    write_json(report, "replay.json")    # every cause, divergence, move, area score, note
    write_junit(report, "replay.xml")    # one test case per area, failed when something diverged there

Files are written atomically (atomicfile): a reader never sees half a report.
"""
from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING
from xml.sax.saxutils import escape, quoteattr

from ..atomicfile import write_atomic

if TYPE_CHECKING:
    from .outcome import ReplayReport

FORMAT = "opentmcl-replay-report"
VERSION = 1


def as_dict(report: ReplayReport) -> dict:
    """The report as plain JSON data (docs/capture.md "Reports")."""
    tol = report.tolerance
    return {
        "format": FORMAT, "version": VERSION, "capture": report.capture, "module": report.module,
        "address": report.address, "ok": report.ok, "compared": report.compared, "skipped": report.skipped,
        "events": report.events, "link": report.link,
        "tolerance": {"time": tol.time, "position": tol.position, "velocity": tol.velocity, "load": tol.load,
                      "timer": tol.timer, "latency": tol.latency},
        "notes": list(report.notes),
        "areas": {area: {"agree": ok, "checks": total, "score": None if not total else round(ok / total, 4)}
                  for area, (ok, total) in report.areas.items()},
        "causes": [{"title": c.title(), "area": c.area, "axis": c.root.axis, "note": c.note,
                    "root": c.root.as_dict(), "repeats": [d.as_dict() for d in c.repeats],
                    "knock_on": [d.as_dict() for d in c.knock_on]} for c in report.causes],
        "divergences": [d.as_dict() for d in report.divergences],
        "moves": [m.as_dict() for m in report.moves],
        "accelerations": {str(axis): {kind: {"module": round(real, 1), "twin": round(twin, 1)}
                                      for kind, (real, twin) in kinds.items()}
                          for axis, kinds in report.accelerations.items()},
        "summary": report.summary(),
    }


def write_json(report: ReplayReport, path: str | os.PathLike[str]) -> None:
    write_atomic(path, (json.dumps(as_dict(report), indent=1) + "\n").encode("utf-8"))


def junit(report: ReplayReport) -> str:
    """JUnit XML: a test suite of the capture, one test case per area that was checked."""
    name = f"opentmcl replay {os.path.basename(report.capture)} against {report.module}"
    cases = []
    failures = 0
    for area, (_agree, total) in report.areas.items():
        if not total:
            continue
        causes = [c for c in report.causes if c.area == area]
        divs = [d for d in report.divergences if d.area == area]
        body = ""
        if divs:
            failures += 1
            lines = [c.title() for c in causes] + [str(d) for d in divs]
            body = (f"<failure message={quoteattr(f'{len(divs)} of {total} checks diverge')} type=\"divergence\">"
                    f"{escape(chr(10).join(lines))}</failure>")
        cases.append(f"  <testcase classname={quoteattr('opentmcl.replay.' + report.module)} "
                     f"name={quoteattr(area)}>{body}</testcase>")
    notes = escape("\n".join([*report.notes, report.summary()]))
    return ("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            f"<testsuite name={quoteattr(name)} tests=\"{len(cases)}\" failures=\"{failures}\" errors=\"0\">\n"
            + "\n".join(cases) + f"\n  <system-out>{notes}</system-out>\n</testsuite>\n")


def write_junit(report: ReplayReport, path: str | os.PathLike[str]) -> None:
    write_atomic(path, junit(report).encode("utf-8"))
