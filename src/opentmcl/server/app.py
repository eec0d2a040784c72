"""A running server: one bus of virtual modules, its clock thread, its endpoints.

    server = Server([VirtualModule("TMCM-6212", address=1)])
    server.add(TcpServer(server.bus, "127.0.0.1", 0))
    server.start()
    ...
    server.stop()        # endpoints closed, EEPROM flushed (vm.close())

While it runs, the EEPROM files are written by a thread of their own (server/eeprom_writer.py).

`stop()` is idempotent and safe to call from a signal-handling main thread.
"""
from __future__ import annotations

import time

from ..faults import FaultBoard, FaultPlan, load_plan
from ..handover import STOP
from .bus import ModuleBus, RealTimeRunner
from .eeprom_writer import EepromWriter


def start_all(endpoints) -> None:
    """Start each endpoint; if one fails, stop those already started and re-raise."""
    started = []
    try:
        for endpoint in endpoints:
            endpoint.start()
            started.append(endpoint)
    except BaseException:
        for endpoint in reversed(started):
            endpoint.stop()
        raise


class Server:
    def __init__(self, modules, *, tick: float = 0.01, faults: object = None) -> None:
        self.bus = ModuleBus(modules)
        self.runner = RealTimeRunner(self.bus, tick=tick)
        self.eeprom_writer = EepromWriter(self.bus)
        """Writes the EEPROM files outside the bus lock while the server runs."""
        self.endpoints: list = []
        self._started = False
        self._stopped = False
        self.faults: FaultBoard | None = None
        """The armed fault plan (docs/faults.md): `faults.trigger(name)`, `faults.log`."""
        if faults is not None or any(_link_plan(vm) for vm in self.bus.modules):
            self.arm(load_plan(faults))

    def arm(self, plan: FaultPlan) -> FaultBoard:
        """Serve with the faults of `plan` and those of the modules' scenarios: link faults on every
        link opened from now on, module faults on their modules; one seed, one log, time in
        seconds since now. FaultError for a fault a module cannot take."""
        start = time.monotonic()
        for vm in self.bus.modules:  # a module's own link faults (its scenario's) act on the links
            own = _link_plan(vm)
            if own:
                plan = plan.merged(own)
        plan.check_addresses(getattr(vm, "address", 1) for vm in self.bus.modules)
        board = FaultBoard(plan, clock=lambda: time.monotonic() - start)
        board.lock = self.bus.lock
        for vm in self.bus.modules:
            faults = getattr(vm, "faults", None)
            if faults is not None:
                faults.load(None, board=board)
        self.faults = self.bus.faults = board
        return board

    @property
    def modules(self) -> list:
        return self.bus.modules

    def add(self, endpoint):
        """Register an endpoint (anything with start() and stop()); returns it."""
        self.endpoints.append(endpoint)
        if self._started:
            endpoint.start()
        return endpoint

    def start(self) -> None:
        """Start the endpoints and the clock; on failure, stop what was started and re-raise."""
        self._started = True
        try:
            start_all(self.endpoints)
        except BaseException:
            self._started = False
            raise
        self.eeprom_writer.start()
        self.runner.start()

    def stop(self) -> None:
        if self._stopped:
            return
        self._stopped = True
        for endpoint in reversed(self.endpoints):
            try:
                endpoint.stop()
            except OSError:
                pass
        self.runner.stop()
        self.eeprom_writer.stop()
        with self.bus.lock.hold(STOP):  # ahead of requests still under way
            for vm in self.bus.modules:
                close = getattr(vm, "close", None)
                if callable(close):
                    close()

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


def _link_plan(vm) -> FaultPlan:
    """The link faults a module was given (its scenario's, `VirtualModule(faults=)`)."""
    own = getattr(getattr(vm, "faults", None), "link_plan", None)
    return own if isinstance(own, FaultPlan) else FaultPlan()
