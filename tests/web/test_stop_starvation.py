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

import importlib
import socket
import threading
import time
from contextlib import contextmanager

import pytest

from .processes import GENEROUS, Served, served_module, wait_for, watcher
from .rawhttp import get_json, post_json

importlib.import_module("uvicorn")

BOUND = 1.0             # seconds, issue 28 "Done when"
ATTEMPTS = 3
SPEED = 5000            # pps: MST ramps it down in about 0.1 s (AP17 = 51200 pps^2)
AXES = 6                # TMCM-6212 manual 1
ROR, MST, GAP, ACTUAL_SPEED = 1, 3, 6, 3


def speeds(client) -> list[int]:
    return [client.reply(GAP, ACTUAL_SPEED, axis).value for axis in range(AXES)]


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
                wait_for(lambda: 200 in statuses, "assembling")
                yield
            finally:
                done.set()
                for t in threads:
                    t.join(GENEROUS)

        times = best_of(served, client, heavy_load)
        assert min(t for _, t in times) < BOUND, times
        assert set(statuses) == {200, 503}, sorted(set(statuses))  # some refused at once: bounded


@pytest.mark.parametrize("mode", ["serve", "dashboard"])
def test_stop_all_during_a_module_scan(mode):
    """Issue 28 item 2: "a running module scan holds the link". A scan of addresses 1..255 with the
    longest time-out per address the dashboard takes (`TIMEOUT_MAX`, 0.5 s, docs/dashboard.md
    "Module scan") runs; STOP ALL is answered and every axis stands within 1 s, on the server's bus
    (`serve --web`, where an address without a module is known to be silent at once, so the scan
    holds the link for a moment per address) and over a TCP link (`dashboard --to`), where the
    scan shares the dashboard's one client and waits its time-out at every empty address."""
    from opentmcl.web.scan import TIMEOUT_MAX

    with served_module(mode) as served, watcher(served) as client:
        @contextmanager
        def scanning():
            r = post_json(served.port, "/api/scan", {"first": 1, "last": 255, "timeout": TIMEOUT_MAX})
            assert r.status == 200, r.body[:300]
            wait_for(lambda: get_json(served.port, "/api/scan")["done"] >= 2, "the scan under way")
            yield

        times = best_of(served, client, scanning)
        assert min(t for _, t in times) < BOUND, times


LOOP = "Loop:\n    ROR 2, 5000\n    WAIT TICKS, 0, 5\n    JA Loop\n"  # manual 3.6.1, 3.6.17, 3.6.9


def program_mode(client) -> int:
    """Command 135 type 1: the mode in the top byte (manual 3.6.36; 0 stop, 1 run)."""
    return (client.reply(135, 1).value & 0xFFFFFFFF) >> 24


def best_time(measure) -> list[float]:
    """Up to ATTEMPTS calls of `measure()` (seconds), stopping at the first within BOUND."""
    times: list[float] = []
    for _ in range(ATTEMPTS):
        times.append(measure())
        print(f"answered and done after {times[-1]:.3f} s")
        if times[-1] < BOUND:
            break
    return times


def test_console_mst_and_program_stop_during_a_module_scan():
    """Issue 28 item 2: "a running module scan holds the link: console MST 0 took 15.1 s, a program
    stop 19.9 s". `opentmcl dashboard --to tcp://...` scans 1..255 at the longest time-out per
    address on its one link; the console's MST 0 (manual 3.6.3) is answered and axis 0 stands
    within 1 s, and the program view's Stop (128, 3.6.36) is answered with the program stopped
    (135 over TCP) within 1 s. Neither cancels the scan."""
    from opentmcl.web.scan import TIMEOUT_MAX

    with served_module("dashboard") as served, watcher(served) as client:
        def scanning() -> None:
            if not get_json(served.port, "/api/scan")["running"]:
                body = {"first": 1, "last": 255, "timeout": TIMEOUT_MAX}
                assert post_json(served.port, "/api/scan", body).status == 200
            wait_for(lambda: get_json(served.port, "/api/scan")["done"] >= 2, "the scan under way")

        def console_mst() -> float:
            client.request(ROR, 0, 0, SPEED)
            wait_for(lambda: client.reply(GAP, ACTUAL_SPEED, 0).value == SPEED, "axis 0 turning")
            scanning()
            start = time.monotonic()
            r = post_json(served.port, "/m/1/api/console", {"line": "MST 0"}, timeout=GENEROUS)
            assert r.status == 200 and r.json()["ok"], r.body[:300]
            wait_for(lambda: client.reply(GAP, ACTUAL_SPEED, 0).value == 0, "axis 0 at speed 0")
            return time.monotonic() - start

        def program_stop() -> float:
            # through the dashboard: its polling waits while it downloads (132..133, manual 3.6.36)
            r = post_json(served.port, "/m/1/api/program/download", {"source": LOOP}, timeout=GENEROUS)
            assert r.status == 200 and r.json()["ok"], r.body[:300]
            client.request(129)  # run (manual 3.6.36)
            wait_for(lambda: program_mode(client) == 1, "the program running")
            scanning()
            start = time.monotonic()
            r = post_json(served.port, "/m/1/api/program/stop", {}, timeout=GENEROUS)
            assert r.status == 200 and r.json()["mode"] == 0, r.body[:300]
            wait_for(lambda: program_mode(client) == 0, "the program stopped")
            return time.monotonic() - start

        assert min(best_time(console_mst)) < BOUND
        assert min(best_time(program_stop)) < BOUND
        assert get_json(served.port, "/api/scan")["running"]  # stops do not end the scan; STOP ALL does
        post_json(served.port, "/api/scan/cancel", {})


def test_a_download_gives_the_link_up_to_a_console_stop():
    """Issue 28: "a download ... gives the link up to a stop". On a link paced at 9600 baud (each
    instruction a round trip of about 19 ms) a download holds the link from 132 to 133 (a command
    sent in between would be stored, manual 3.6.36); the console's MST 0 ends it between two
    instructions: the download leaves download mode (133) and answers that a stop cancelled it,
    and MST 0 is answered within 1 s and axis 0 stands (GAP over TCP)."""
    source = "\n".join(f"    MVP ABS, 0, {i}" for i in range(1000)) + "\n    STOP\n"
    with served_module("paced") as served, watcher(served) as client:
        client.request(ROR, 0, 0, SPEED)  # before the download: a request meanwhile would be stored
        wait_for(lambda: client.reply(GAP, ACTUAL_SPEED, 0).value == SPEED, "axis 0 turning")
        assert get_json(served.port, "/m/1/api/state")["download"] is None  # the state is there to poll
        answers: list = []
        downloading = threading.Thread(daemon=True, target=lambda: answers.append(
            post_json(served.port, "/m/1/api/program/download", {"source": source}, timeout=120)))
        downloading.start()
        wait_for(lambda: (get_json(served.port, "/m/1/api/state")["download"] or [0])[0] >= 5,
                 "the download under way")
        start = time.monotonic()
        r = post_json(served.port, "/m/1/api/console", {"line": "MST 0"}, timeout=GENEROUS)
        answered = time.monotonic() - start
        downloading.join(GENEROUS)
        assert r.status == 200 and r.json()["ok"], r.body[:300]
        assert answers[0].status == 400 and "cancelled by a stop command" in answers[0].error, answers[0].body
        wait_for(lambda: client.reply(GAP, ACTUAL_SPEED, 0).value == 0, "axis 0 at speed 0")
        print(f"MST 0 answered after {answered:.3f} s")
        assert answered < BOUND
