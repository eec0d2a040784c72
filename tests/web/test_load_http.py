"""Load on the dashboard's HTTP API over real sockets: the page's own readers and writers run at the
same time as forgers (cross-site form POSTs, rebound Host names) and 64 MiB bodies. Every own
request is served, every forged one refused (403/413), and the forgers change nothing. A few
hundred requests in CI, 16000 behind the `slow` marker."""
from __future__ import annotations

import importlib
import json
from concurrent.futures import ThreadPoolExecutor

import pytest

from .rawhttp import page_headers, post_json, request, send_raw

importlib.import_module("uvicorn")

FORGED_TARGET = 9999


@pytest.fixture(scope="module")
def dash():
    """A dashboard on the wall clock with its poller running, as `opentmcl dashboard` serves it."""
    import opentmcl
    from opentmcl.web import start_dashboard

    module = opentmcl.connect("sim://TMCM-6212?clock=real")
    transport = module.client.transport
    with start_dashboard(module, "127.0.0.1", 0, vm=transport.module, vm_lock=transport.lock,
                         on_stop=module.close) as handle:
        handle.dashboard.download("    CALC LOAD, 0\nLoop:\n    CALC ADD, 1\n    JA Loop\n")
        yield handle


def own_read(port: int, i: int) -> int:
    return request(port, "GET", ("/m/1/api/state", "/m/1/api/params/axis/1", "/m/1/")[i % 3]).status


def own_write(port: int, i: int) -> int:
    """Manual 3.6.6 GAP 1 (actual position) through the console: a state-changing route."""
    r = post_json(port, "/m/1/api/console", {"line": "GAP 1, 0"})
    return r.status if r.status != 200 or r.json()["status"] == 100 else -1


def forged(port: int, i: int) -> int:
    if i % 2:
        return request(port, "POST", "/m/1/api/program/run", body=b"x=1",
                       headers={"Origin": "http://evil.example",
                                "Content-Type": "application/x-www-form-urlencoded"}).status
    return post_json(port, "/m/1/api/console", {"line": f"MVP ABS, 0, {FORGED_TARGET}"},
                     host=f"rebind.example:{port}", headers={"Origin": f"http://rebind.example:{port}"}).status


def huge(port: int, i: int) -> int:
    head = (f"POST /m/1/api/program/download HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nX-OpenTMCL: 1\r\n"
            f"Content-Type: application/json\r\nContent-Length: {64 << 20}\r\n\r\n").encode()
    return send_raw(port, head + json.dumps({"source": "x" * 1000}).encode()[:-1]).status


KINDS = [(own_read, 200), (own_write, 200), (forged, 403), (huge, 413)]


def hammer(handle, workers: int, per_worker: int) -> dict:
    """`workers` threads, each `per_worker` requests of one kind; the statuses seen per kind."""
    port = handle.port

    def worker(w: int) -> tuple[str, list[int]]:
        fn, _ = KINDS[w % len(KINDS)]
        return fn.__name__, [fn(port, i) for i in range(per_worker)]

    seen: dict = {}
    with ThreadPoolExecutor(workers) as pool:
        for name, statuses in pool.map(worker, range(workers)):
            seen.setdefault(name, []).extend(statuses)
    return seen


def check(handle, workers: int, per_worker: int) -> None:
    d = handle.dashboard
    seen = hammer(handle, workers, per_worker)
    for fn, expected in KINDS:
        statuses = seen[fn.__name__]
        assert statuses and set(statuses) == {expected}, (fn.__name__, sorted(set(statuses)))
    assert sum(map(len, seen.values())) == workers * per_worker
    assert d.program_state()["mode_name"] != "run"       # manual 3.6.36: 129 never arrived
    assert d.module.axes[0].target_position != FORGED_TARGET  # manual 3.6.4: MVP never arrived
    assert request(handle.port, "POST", "/m/1/api/program/stop", headers=page_headers(handle.port)).status == 200


def test_load_own_and_forged_requests(dash):
    check(dash, workers=8, per_worker=30)


@pytest.mark.slow
def test_load_own_and_forged_requests_long(dash):
    check(dash, workers=16, per_worker=1000)
