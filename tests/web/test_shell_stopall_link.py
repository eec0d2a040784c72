"""Stop-all and the module scan on one link (issue 14 item 1: "sends MST to every axis of every
module on the bus"; docs/dashboard.md "Stop all"): a running scan cannot hold stop-all back, and a
module the scan found is stopped even when the dashboard does not serve it. The motors are read
back over the wire (GAP 2, target speed, TMCM-6212 manual 4.1)."""
from __future__ import annotations

import importlib

from .test_shell_scan import call, scan_to_end

importlib.import_module("starlette")
importlib.import_module("uvicorn")

ROR, GAP, TARGET_SPEED = 1, 6, 2


def test_stop_all_cancels_a_baud_rate_scan_and_stops_the_motor():
    """A baud-rate scan holds the serial link (docs/dashboard.md "Module scan": the dashboard's own
    polling is held meanwhile). STOP ALL during it cancels the scan after its current address and
    sends MST (manual 3.6.3) at once: the scan reports cancelled with addresses left unasked, and
    motor 0 of the TMCM-6212 turned by ROR (3.6.1) has target speed 0 when stop-all answers."""
    import opentmcl
    from opentmcl import VirtualModule
    from opentmcl.server.app import Server
    from opentmcl.server.pty import PtyServer
    from opentmcl.web import start_dashboard

    server = Server([VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)])
    pty = server.add(PtyServer(server.bus))
    server.start()
    link = opentmcl.connect(f"serial://{pty.path}?baud=9600")
    handle = start_dashboard(link, "127.0.0.1", 0)
    try:
        link.request(ROR, 0, 0, 30000)
        status, st = call(handle, "POST", "/api/scan", {"first": 3, "last": 255, "timeout": 0.05,
                                                        "bauds": [9600, 19200]})
        assert status == 200 and st["running"]
        status, out = call(handle, "POST", "/api/stop-all", {})
        assert status == 200 and out["ok"]
        assert link.reply(GAP, TARGET_SPEED, 0).value == 0
        scan = call(handle, "GET", "/api/scan")[1]
        assert not scan["running"] and scan["cancelled"] and scan["done"] < scan["total"] == 2 * 253
        assert out["scan_cancelled"]
        assert link.client.transport.baud == 9600  # the link is back at its own rate
    finally:
        handle.stop()
        link.close()
        server.stop()


def test_stop_all_stops_a_module_the_scan_found_but_the_dashboard_does_not_serve():
    """`opentmcl dashboard --to tcp://...` serves address 1; the scan finds the PD86-1180 at 2 on
    the same link. ROR 0, 1000 turns its motor (PD86-1180 manual 4.6.1); STOP ALL sends it MST
    (4.6.3) too, and lists it in its result; its target speed reads 0 afterwards."""
    import opentmcl
    from opentmcl.web import start_dashboard

    from .shellkit import bench

    with bench(("TMCM-6212", 1), ("PD86-1180", 2)) as b:
        link = opentmcl.connect(b.url)
        handle = start_dashboard(link, "127.0.0.1", 0, url=b.url, on_stop=link.close)
        try:
            found = scan_to_end(handle, {"first": 1, "last": 3, "timeout": 0.05})["found"]
            assert [(f["address"], f["served"]) for f in found] == [(1, True), (2, False)]
            one = b.client(2)
            one.request(ROR, 0, 0, 1000)
            status, out = call(handle, "POST", "/api/stop-all", {})
            assert status == 200 and out["ok"]
            assert one.client.reply(GAP, TARGET_SPEED, 0).value == 0
            assert [(m["address"], m["module"], m["axes_stopped"]) for m in out["modules"]] == \
                [(1, "TMCM-6212", [0, 1, 2, 3, 4, 5]), (2, "PD86-1180", [0])]
            assert out["scan_cancelled"] is False
        finally:
            handle.stop()


# Motor 2 turns while the program waits 3 s (WAIT TICKS: "one tick is 10 milliseconds", manual 3.6.20); line 3
# holds the breakpoint the dashboard single-steps to (docs/dashboard.md "Views", Program).
STEPPED = "ROR 2, 30000\nWAIT TICKS, 0, 300\nMST 2\nStop:\n    JA Stop\n"


def test_stop_all_does_not_wait_for_a_stepped_wait():
    """Issue 14 item 1: stop-all "works while a program runs (it also stops the program)". With a
    breakpoint, Run single-steps (130) towards it; STOP ALL during the stepped WAIT sends 128 (manual
    3.6.36 "Stop application") at once: the program stops in its WAIT (135 type 1: PC 1) instead
    of reaching the breakpoint at PC 2 first, and motor 2 (ROR, 3.6.1) gets MST (target speed 0)."""
    from opentmcl.host.loader import Loader

    from .shellkit import bench, wait_until

    with bench(("TMCM-6212", 1)) as b:
        h = b.handle
        assert call(h, "POST", "/m/1/api/program/download", {"source": STEPPED})[0] == 200
        assert call(h, "POST", "/m/1/api/program/breakpoints", {"lines": [3]})[1] == {"addresses": [2]}
        assert call(h, "POST", "/m/1/api/program/run", {})[0] == 200
        six = b.client(1)
        wait_until(lambda: Loader(six).status().waiting, "the program in its WAIT")
        status, out = call(h, "POST", "/api/stop-all", {})
        assert status == 200 and out["ok"]
        st = Loader(six).status()
        assert (st.mode, st.pc) == (0, 1)
        assert six.client.reply(GAP, TARGET_SPEED, 2).value == 0
        assert call(h, "GET", "/m/1/api/program")[1]["state"]["stepping_to_breakpoint"] is False


def test_stop_all_ends_a_download_under_way():
    """Between 132 "enter download mode" and 133 "exit download mode" commands "are not executed but
    stored in the TMCL memory" (manual 3.6.36), so the dashboard holds the module for the whole
    download. STOP ALL during a long download ends it at the next instruction (133 sent), then
    sends MST: motor 0 turned by ROR (3.6.1) gets target speed 0, the module is out of download
    mode, and the download is answered with a one-line error naming STOP ALL."""
    import threading
    import time

    from .shellkit import bench, wait_until

    source = "ROR 1, 1000\n" * 4000 + "Stop:\n    JA Stop\n"
    with bench(("TMCM-6212", 1)) as b:
        h = b.handle
        vm = b.server.bus.modules[0]
        store = vm.store_instruction

        def slow_store(*args):  # a real module writes each instruction to its EEPROM: the download
            time.sleep(0.0005)  # lasts at least 2 s, however fast the request path is
            return store(*args)

        vm.store_instruction = slow_store
        six = b.client(1)
        six.request(ROR, 0, 0, 30000)
        answer: list = []
        loading = threading.Thread(target=lambda: answer.append(
            call(h, "POST", "/m/1/api/program/download", {"source": source})))
        loading.start()
        try:
            wait_until(lambda: vm.download_mode, "the module in download mode", every=0.001)
            status, out = call(h, "POST", "/api/stop-all", {})
        finally:
            loading.join(60)
        assert status == 200 and out["ok"]
        assert answer[0][0] == 400 and "STOP ALL" in answer[0][1]["error"]
        assert not vm.download_mode
        assert six.client.reply(GAP, TARGET_SPEED, 0).value == 0
