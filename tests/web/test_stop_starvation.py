"""Issue 28 item 2: "A STOP ALL path that nothing can starve". Real processes only: a served
TMCM-6212 (`opentmcl serve --web`, or `opentmcl dashboard --to tcp://...` in front of one) and the
test's own TCP client, which watches the motors with GAP 3 "actual speed" (TMCM-6212 manual 4.1,
3.6.6) over a connection of its own, never through the dashboard.

Done when (issue 28): "STOP ALL answered and every axis at speed 0 within 1 s under each
starvation of item 2": 300 idle sockets to the web port, 45 heavy assemble requests in flight, a
running module scan. The second is measured from the POST to the moment the last GAP 3 answers 0;
the axes turn at 5000 pps, which MST (3.6.3) ramps down with AP17's default deceleration of 51200
pps^2 in about 0.1 s. The 1 s is the issue's own bound on real processes: a busy machine (other
test runs) can delay any one attempt, so each scenario takes the best of `ATTEMPTS`; the old code
needed 13-35 s or never answered, in every attempt.
"""
from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time
import urllib.parse
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import pytest

from .rawhttp import get_json, post_json, start_cli, stop_cli

pytest.importorskip("uvicorn", reason="the dashboard needs the web extra")

BOUND = 1.0             # seconds, issue 28 "Done when"
ATTEMPTS = 3
SPEED = 5000            # pps: MST ramps it down in about 0.1 s (AP17 = 51200 pps^2)
AXES = 6                # TMCM-6212 manual 1
ROR, MST, GAP, ACTUAL_SPEED = 1, 3, 6, 3
GENEROUS = 30.0         # a guard against hanging, never a timing assert


@dataclass
class Served:
    port: int           # the dashboard's
    tcp: str            # tcp://HOST:PORT of the module


def _tcp_url(lines: list[str]) -> str:
    return next(line.split()[-1] for line in lines if line.strip().startswith("tcp "))


@contextmanager
def served_module(mode: str) -> Iterator[Served]:
    """"serve": `opentmcl serve --web`; "dashboard": `opentmcl serve` and `opentmcl dashboard --to`."""
    args = ["serve", "--module", "TMCM-6212", "--tcp", "127.0.0.1:0"]
    if mode == "serve":
        proc, url, lines = start_cli([*args, "--web", "127.0.0.1:0"], "dashboard http")
        try:
            yield Served(urllib.parse.urlsplit(url).port, _tcp_url(lines))
        finally:
            out = stop_cli(proc)
            assert "Traceback" not in out, out
        return
    module = subprocess.Popen([sys.executable, "-m", "opentmcl", *args], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True)
    try:
        lines = []
        for line in module.stdout:
            lines.append(line)
            if line.strip().startswith("tcp "):
                break
        tcp = _tcp_url(lines)
        proc, url, _ = start_cli(["dashboard", "--to", tcp, "--web", "127.0.0.1:0"], "dashboard for")
        try:
            yield Served(urllib.parse.urlsplit(url).port, tcp)
        finally:
            out = stop_cli(proc)
            assert "Traceback" not in out, out
    finally:
        stop_cli(module)


@contextmanager
def watcher(served: Served):
    """The test's own TCP client of the module (a second connection, not the dashboard's)."""
    from opentmcl.host import Client
    from opentmcl.host.transports.tcp import TcpTransport

    host, port = served.tcp.removeprefix("tcp://").rsplit(":", 1)
    client = Client(TcpTransport(host, int(port)), timeout=10.0)
    try:
        yield client
    finally:
        client.close()


def speeds(client) -> list[int]:
    return [client.reply(GAP, ACTUAL_SPEED, axis).value for axis in range(AXES)]


def wait_for(predicate, what: str) -> None:
    end = time.monotonic() + GENEROUS
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"not reached: {what}")
        time.sleep(0.02)


def all_turning(client) -> None:
    """ROR on every axis (manual 3.6.1), until every one turns at SPEED."""
    for axis in range(AXES):
        client.request(ROR, 0, axis, SPEED)
    wait_for(lambda: speeds(client) == [SPEED] * AXES, "every axis at speed")


def stop_all_time(served: Served, client) -> tuple[float, float]:
    """POST /api/stop-all: (seconds to its answer, seconds until GAP 3 reads 0 on every axis)."""
    start = time.monotonic()
    r = post_json(served.port, "/api/stop-all", {}, timeout=GENEROUS)
    answered = time.monotonic() - start
    assert r.status == 200, r.body[:300]
    assert r.json()["ok"] and r.json()["modules"][0]["axes_stopped"] == list(range(AXES)), r.body[:300]
    wait_for(lambda: speeds(client) == [0] * AXES, "every axis at speed 0")
    return answered, time.monotonic() - start


def best_of(served: Served, client, starve) -> list[tuple[float, float]]:
    """Up to ATTEMPTS rounds of: every axis turning, `starve()` (a context manager), STOP ALL
    timed; stops at the first round within BOUND. Every round's times, for the message."""
    times = []
    for _ in range(ATTEMPTS):
        all_turning(client)
        with starve():
            times.append(stop_all_time(served, client))
        print(f"STOP ALL answered after {times[-1][0]:.3f} s, every axis at 0 after {times[-1][1]:.3f} s")
        if times[-1][1] < BOUND:
            break
    return times


def test_stop_all_with_300_idle_sockets_held_open():
    """Issue 28 item 2: "300 idle sockets to the web port fill the 64-connection cap: 7 of 7 STOP
    ALL requests were closed unanswered". With 300 sockets connected and silent, STOP ALL is
    answered and every axis stands within 1 s; a plain GET is answered too (the longest-idle
    connection gives its place up, docs/dashboard.md "Threat model")."""
    with served_module("serve") as served, watcher(served) as client:
        @contextmanager
        def idle_sockets():
            held = [socket.create_connection(("127.0.0.1", served.port), timeout=GENEROUS) for _ in range(300)]
            try:
                assert get_json(served.port, "/api/modules")[0]["module"] == "TMCM-6212"
                yield
            finally:
                for sock in held:
                    sock.close()

        times = best_of(served, client, idle_sockets)
        assert min(t for _, t in times) < BOUND, times


HEAVY = "\n".join(f"L{i}: MVP ABS, 0, {i}\n    JA L{i}" for i in range(3000))  # 6000 instructions


def test_stop_all_with_45_heavy_assemble_requests_in_flight():
    """Issue 28 item 2: "with 45 heavy assemble requests in flight it answered after 35.6 s".
    45 threads each keep one assemble of a 6000-instruction source in flight (a new one as soon
    as one is answered); STOP ALL is answered and every axis stands within 1 s. The long requests
    are bounded: some of them are answered 503 (busy) at once instead of piling up."""
    with served_module("serve") as served, watcher(served) as client:
        statuses: list[int] = []

        @contextmanager
        def heavy_load():
            done = threading.Event()

            def keep_one_in_flight() -> None:
                while not done.is_set():
                    try:
                        r = post_json(served.port, "/m/1/api/program/assemble", {"source": HEAVY}, timeout=120)
                        statuses.append(r.status)
                    except OSError:
                        statuses.append(0)

            threads = [threading.Thread(target=keep_one_in_flight, daemon=True) for _ in range(45)]
            for t in threads:
                t.start()
            try:
                wait_for(lambda: 200 in statuses and 503 in statuses, "assembling and refusing")
                yield
            finally:
                done.set()
                for t in threads:
                    t.join(GENEROUS)

        times = best_of(served, client, heavy_load)
        assert min(t for _, t in times) < BOUND, times
        assert set(statuses) <= {200, 503}, sorted(set(statuses))


@pytest.mark.parametrize("mode", ["serve", "dashboard"])
def test_stop_all_during_a_module_scan(mode):
    """Issue 28 item 2: "a running module scan holds the link". A scan of addresses 1..255 with the
    longest time-out per address (0.5 s, docs/dashboard.md "Module scan") runs; STOP ALL is answered
    and every axis stands within 1 s, on the server's bus (`serve --web`) and over a TCP link
    (`dashboard --to`), where the scan shares the dashboard's one client."""
    with served_module(mode) as served, watcher(served) as client:
        @contextmanager
        def scanning():
            r = post_json(served.port, "/api/scan", {"first": 1, "last": 255, "timeout": 0.5})
            assert r.status == 200, r.body[:300]
            wait_for(lambda: get_json(served.port, "/api/scan")["done"] >= 2, "the scan under way")
            yield

        times = best_of(served, client, scanning)
        assert min(t for _, t in times) < BOUND, times
