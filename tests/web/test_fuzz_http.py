"""Fuzzing the dashboard's HTTP API over real sockets (hypothesis): generated methods, paths, headers
and bodies. The invariants (issue 11): never a server error or a traceback, every error one line;
a request that is not the page's own (foreign Host or Origin, no X-OpenTMCL header) gets 403 and
changes nothing; the dashboard keeps answering. 60 examples in CI, more with HYPOTHESIS_PROFILE=long,
several thousand behind the `slow` marker."""
from __future__ import annotations

import importlib
import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from .rawhttp import request

importlib.import_module("uvicorn")

ROUTES = ["/", "/api/modules", "/m/1/", "/m/1/api/overview", "/m/1/api/state", "/m/1/api/params/axis/0",
          "/m/1/api/params/axis", "/m/1/api/params/global", "/m/1/api/params/store", "/m/1/api/console",
          "/m/1/api/io/output", "/m/1/api/io/force", "/m/1/api/program", "/m/1/api/program/assemble",
          "/m/1/api/program/download", "/m/1/api/program/run", "/m/1/api/program/stop",
          "/m/1/api/program/step", "/m/1/api/program/reset", "/m/1/api/program/breakpoints",
          "/m/2/api/overview", "/static/app.js", "/m/1/ws"]
KEYS = ["line", "source", "axis", "number", "value", "bank", "port", "kind", "index", "restore", "lines"]
SAFE = ("GET", "HEAD")

segment = st.text("abcdefghijklmnopqrstuvwxyz0123456789-._~%", max_size=12)
paths = st.one_of(st.sampled_from(ROUTES),
                  st.builds(lambda a, rest: a + "/".join(rest), st.sampled_from(["/", "/m/1/", "/m/1/api/", "/static/"]),
                            st.lists(segment, max_size=4)),
                  st.builds(lambda r, q: f"{r}?{q}", st.sampled_from(ROUTES), segment))
values = st.recursive(st.one_of(st.none(), st.booleans(), st.integers(-(2**70), 2**70), st.text(max_size=30),
                                st.sampled_from(["MVP ABS, 0, 1000", "GAP 1, 0", "1" * 5000, "0x" + "f" * 100,
                                                 "    STOP\n", "#include </etc/hostname>\n", "axis"])),
                      lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.sampled_from(KEYS), inner, max_size=3),
                      max_leaves=8)
bodies = st.one_of(st.just(b""), st.binary(max_size=200),
                   st.dictionaries(st.sampled_from(KEYS), values, max_size=5).map(lambda d: json.dumps(d).encode()),
                   values.map(lambda v: json.dumps(v).encode()))
origins = st.sampled_from([None, "own", "http://evil.example", "null", "http://127.0.0.1:1", "own-https"])
hosts = st.sampled_from(["own", "localhost", "rebind.example", "rebind.example:{port}"])
headers = st.fixed_dictionaries({"origin": origins, "host": hosts,
                                 "marker": st.sampled_from([None, "1", "0", "yes"]),
                                 "type": st.sampled_from([None, "application/json", "text/plain",
                                                          "application/x-www-form-urlencoded"])})


@pytest.fixture(scope="module")
def dash():
    """A dashboard in this process on a real socket (virtual clock: nothing moves by itself)."""
    import opentmcl
    from opentmcl.web import start_dashboard

    module = opentmcl.connect("sim://TMCM-6212")
    transport = module.client.transport
    with start_dashboard(module, "127.0.0.1", 0, vm=transport.module, vm_lock=transport.lock,
                         on_stop=module.close, poll=False) as handle:
        handle.dashboard.download("    CALC LOAD, 0\nLoop:\n    CALC ADD, 1\n    JA Loop\n")
        yield handle


def snapshot(handle) -> tuple:
    """What a forged request could change: program mode/PC/A, every axis's target (AP 0) and max
    speed (AP 4), the I/O ports (TMCM-6212 manual 3.6.36, 4.1, 3.6.12/3.6.13)."""
    d = handle.dashboard
    st_ = d.program_state()
    axes = d.module.axes
    return ((st_["mode"], st_["pc"], st_["a"]), tuple(a.target_position for a in axes),
            tuple(a.get(4) for a in axes), json.dumps(d.read_io()))


def is_own(h: dict, method: str) -> bool:
    """The page's own request, or a script's: a loopback Host; for a state-changing one also no
    Origin or the dashboard's (https too: behind a TLS proxy, docs/assumptions.md) and X-OpenTMCL: 1."""
    own_host = h["host"] in ("own", "localhost")
    if method in SAFE:
        return own_host
    return own_host and h["origin"] in (None, "own", "own-https") and h["marker"] == "1"


def send(handle, method: str, path: str, h: dict, body: bytes):
    port = handle.port
    host = {"own": f"127.0.0.1:{port}", "localhost": "localhost"}.get(h["host"], h["host"].format(port=port))
    hdrs = {}
    if h["origin"] is not None:
        hdrs["Origin"] = {"own": f"http://{host}", "own-https": f"https://{host}"}.get(h["origin"], h["origin"])
    if h["marker"] is not None:
        hdrs["X-OpenTMCL"] = h["marker"]
    if h["type"] is not None:
        hdrs["Content-Type"] = h["type"]
    return request(port, method, path, host=host, headers=hdrs, body=body)


def check(handle, method: str, path: str, h: dict, body: bytes) -> None:
    own = is_own(h, method)
    before = None if own else snapshot(handle)
    r = send(handle, method, path, h, body)
    assert r.status < 500, (method, path, h, r.status, r.body[:300])
    assert b"Traceback" not in r.body
    if r.status in (400, 403, 404, 413) and method != "HEAD" and \
            r.headers.get("content-type", "").startswith("application/json"):
        error = r.json()["error"]
        assert "\n" not in error and len(error) <= 400, error
    if not own:
        assert r.status == 403, (method, path, h, r.status, r.body[:300])
        assert snapshot(handle) == before, (method, path, h)
    assert request(handle.port, "GET", "/m/1/api/overview").status == 200  # still serving


METHODS = st.sampled_from(["GET", "HEAD", "POST", "POST", "POST", "PUT", "DELETE", "PATCH", "OPTIONS"])
FUZZ = settings(deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


@FUZZ
@given(method=METHODS, path=paths, h=headers, body=bodies)
def test_fuzzed_requests(dash, method, path, h, body):
    check(dash, method, path, h, body)


@pytest.mark.slow
@settings(FUZZ, max_examples=3000)
@given(method=METHODS, path=paths, h=headers, body=bodies)
def test_fuzzed_requests_long(dash, method, path, h, body):
    check(dash, method, path, h, body)
