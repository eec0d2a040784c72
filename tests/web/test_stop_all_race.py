"""STOP ALL against a Run or Step that arrived before it but is sent after it (docs/dashboard.md
"Stop all"; the dashboard's rule "refuse what its owner did not ask for"). A request whose thread
was held up (a busy machine, a browser's six connections) must not start the program again once
STOP ALL (128, TMCM-6212 manual 3.6.36: "stop a running TMCL program") has stopped it."""
from __future__ import annotations

import pytest

from opentmcl.web import motion
from opentmcl.web.service import DashboardError

PROGRAM = "Loop:\n    MVP ABS, 0, 100000\n    WAIT TICKS, 0, 1\n    JA Loop\n"


def _status(client):
    return client.dash.program_state()["mode"]


@pytest.mark.parametrize("action", ["run", "step"])
def test_a_run_or_step_from_before_stop_all_is_refused(client, action):
    """The request arrived (stops counted then), STOP ALL came, then the request is carried out:
    it is refused as "cancelled by STOP ALL", the program stays as the download left it (135 mode 3,
    reset: the dashboard's download ends with 131, docs/dashboard-program.md; not 1, run) and no
    move was started (GAP 0, target position, stays 0)."""
    d = client.dash
    d.download(PROGRAM)
    arrived = d.stops
    assert motion.stop_module(d)["ok"]
    with pytest.raises(DashboardError, match="cancelled by STOP ALL"):
        getattr(d, action)(arrived)
    assert _status(client) == 3
    assert client.module.reply(6, 0, 0).value == 0


@pytest.mark.parametrize("action", ["run", "step"])
def test_a_run_or_step_after_stop_all_is_carried_out(client, action):
    """A request that arrived after the STOP ALL is what the owner asked for: it runs (the first
    instruction, MVP ABS 0, 100000, sets the target position, manual 3.6.4)."""
    d = client.dash
    d.download(PROGRAM)
    motion.stop_module(d)
    getattr(d, action)(d.stops)
    client.module.client.sleep(0.05)
    assert client.module.reply(6, 0, 0).value == 100000


def test_the_http_step_counts_stops_at_arrival(client):
    """POST api/program/step after a STOP ALL is carried out: the count is taken when it arrives."""
    d = client.dash
    d.download(PROGRAM)
    assert client.post("/api/stop-all").status_code == 200
    assert client.post("/m/1/api/program/step", json={}).status_code == 200
    assert client.module.reply(6, 0, 0).value == 100000
